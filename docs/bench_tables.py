#!/usr/bin/env python3
"""The transport tables of docs/performance.md, made from `afhub bench --json` files.

    docs/bench_tables.py docs/bench_touch.json           # medians with ratios, then p99s
    docs/bench_tables.py docs/bench.json docs/bench_touch.json --loop   # the 1 kHz loop

One-way latency in us; a median's ratio is to afhub's queue at the same size. With
--loop, two runs side by side (the first / the second). tests/docs_figures_test.py checks
that the page holds exactly what this prints for the files it was made from. Standard
library only."""
import json
import sys

SIZES = [64, 1024, 16384, 262144, 1048576]
# Transport, its row in the medians' table, its row in the p99s'.
ROWS = [
    ("afhub", None, "afhub (queue)"),
    ("afhub-slot", "afhub-slot (states, commands)", "afhub-slot"),
    ("shm-floor", "bare shared memory (the floor)", "bare shared memory"),
    ("dds", "Cyclone DDS", "Cyclone DDS"),
    ("dds-shm", "Cyclone DDS, its shared memory on", "Cyclone DDS, shared memory"),
    ("uds", "Unix sockets", "Unix sockets"),
    ("ros1", "ROS 1", "ROS 1"),
]


def size_name(size):
    return f"{size // 1048576} MiB" if size >= 1048576 else (
        f"{size // 1024} KiB" if size >= 1024 else f"{size} B")


def us(value):
    return f"{value:.0f}" if value >= 1000 else f"{value:.1f}"


def ratio(value):
    return f"{value:.0f}x" if value >= 10 else f"{value:.1f}x"


def header(title):
    return [f"| {title} | " + " | ".join(size_name(s) for s in SIZES) + " |",
            "| --- " * (len(SIZES) + 1) + "|"]


def transport_tables(run):
    transports = run["transports"]
    queue = transports["afhub"]
    queue_name = "afhub (queue, read in place)" if run["settings"]["touch"] else (
        "afhub (queue, zero copy)")
    median = header("median")
    p99 = header("p99")
    for key, median_name, p99_name in ROWS:
        if key not in transports:
            continue
        cells = []
        for size in SIZES:
            value = transports[key][str(size)]["p50_us"]
            cells.append(us(value) if key == "afhub" else
                         f"{us(value)} ({ratio(value / queue[str(size)]['p50_us'])})")
        median.append(f"| {median_name or queue_name} | " + " | ".join(cells) + " |")
        p99.append(f"| {p99_name} | " +
                   " | ".join(us(transports[key][str(s)]["p99_us"]) for s in SIZES) + " |")
    return "\n".join(median) + "\n\n" + "\n".join(p99) + "\n"


def loop_table(first, second):
    fields = ["p50", "p99", "p999", "max"]

    def row(name, key):
        cells = (f"{first['loop_jitter'][key][f]:.0f} / {second['loop_jitter'][key][f]:.0f}"
                 for f in fields)
        return f"| {name} | " + " | ".join(cells) + " |"

    def name(run):
        return "the `--touch` run" if run["settings"]["touch"] else "the stamps-alone run"

    seconds = first["settings"]["loop_seconds"]
    return "\n".join([
        f"| 1 kHz loop, {seconds:g} s, wake-up latency (us), {name(first)} / {name(second)} "
        "| p50 | p99 | p99.9 | max |",
        "| --- | --- | --- | --- | --- |",
        row("afhub controller beside `afhub run` on the example arm", "afhub_us"),
        row("cyclictest in the same seconds", "cyclictest_us"),
    ]) + "\n"


def main(args):
    loop = "--loop" in args
    paths = [a for a in args if a != "--loop"]
    if not paths or (loop and len(paths) != 2):
        sys.exit(__doc__.split("\n\n")[1])
    runs = []
    for path in paths:
        with open(path) as f:
            runs.append(json.load(f))
    if loop:
        print(loop_table(*runs), end="")
    else:
        print("\n".join(transport_tables(run) for run in runs), end="")


if __name__ == "__main__":
    main(sys.argv[1:])
