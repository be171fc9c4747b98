"""Screenshot checks for the viewer test (Debian python3-pil).
  pixels.py count FILE          pixels far from the page's background (#20262e)
  pixels.py differ FILE1 FILE2  pixels that differ between two screenshots
Prints one number."""
import sys

from PIL import Image, ImageChops

BACKGROUND = (0x20, 0x26, 0x2E)
TOLERANCE = 40  # the floor grid's lines stay within it


def far_from_background(pixel):
    return any(abs(c - b) > TOLERANCE for c, b in zip(pixel[:3], BACKGROUND))


def main():
    if sys.argv[1] == "count":
        image = Image.open(sys.argv[2]).convert("RGB")
        print(sum(1 for p in image.getdata() if far_from_background(p)))
    else:
        a = Image.open(sys.argv[2]).convert("RGB")
        b = Image.open(sys.argv[3]).convert("RGB")
        difference = ImageChops.difference(a, b).convert("L")
        print(sum(1 for v in difference.getdata() if v > 16))


main()
