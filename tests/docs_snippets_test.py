#!/usr/bin/env python3
"""The code in README.md and docs/ is true: every C++ block compiles against the
project's headers, every shell block parses, and every `afhub` command line in a shell
block names a real subcommand and only options that subcommand's --help lists.

    docs_snippets_test.py SOURCE_DIR AFHUB_EXECUTABLE
"""
import pathlib
import re
import shlex
import subprocess
import sys
import tempfile

source = pathlib.Path(sys.argv[1])
afhub = sys.argv[2]
pages = [source / "README.md"] + sorted((source / "docs").glob("*.md"))
includes = [f"-I{d}" for d in sorted(source.glob("*/include")) + sorted(source.glob("*/*/include"))]
includes += ["-I/usr/include/iceoryx/v2.0.3"]
failures = []
checked = {"cpp": 0, "sh": 0, "afhub": 0}


def blocks(page):
    """(language, first line number, text) of each fenced block."""
    lines = page.read_text().splitlines()
    i = 0
    while i < len(lines):
        m = re.match(r"^```(\w*)\s*$", lines[i])
        if m and m.group(1):
            start, body = i + 1, []
            i += 1
            while i < len(lines) and not lines[i].startswith("```"):
                body.append(lines[i])
                i += 1
            yield m.group(1), start + 1, "\n".join(body) + "\n"
        i += 1


help_of = {}


def help_text(words):
    key = tuple(words)
    if key not in help_of:
        run = subprocess.run([afhub, *words, "--help"], capture_output=True, text=True, timeout=30)
        help_of[key] = run.stdout if run.returncode == 0 else None
    return help_of[key]


def check_command_line(where, line):
    tokens = shlex.split(line, comments=True)
    if not tokens or not tokens[0].endswith("afhub"):
        return
    checked["afhub"] += 1
    words = []
    for token in tokens[1:]:
        if not re.fullmatch(r"[a-z][a-z0-9-]*", token):
            break
        words.append(token)
    # The longest prefix of the words that is a subcommand (the rest are arguments).
    while words and help_text(words) is None:
        words.pop()
    text = help_text(words)
    if text is None:
        failures.append(f"{where}: `afhub` does not answer --help: {line}")
        return
    for token in tokens[1:]:
        option = token.split("=", 1)[0]
        if re.fullmatch(r"--[a-z][a-z0-9-]*", option) and not re.search(
            re.escape(option) + r"\b", text
        ):
            failures.append(
                f"{where}: `afhub {' '.join(words)}` has no option {option}: {line}"
            )


with tempfile.TemporaryDirectory() as scratch:
    for page in pages:
        for language, line, text in blocks(page):
            where = f"{page.relative_to(source)}:{line}"
            if language == "cpp":
                checked["cpp"] += 1
                snippet = pathlib.Path(scratch) / "snippet.cpp"
                snippet.write_text(text)
                run = subprocess.run(
                    ["g++", "-std=c++20", "-fsyntax-only", "-Wall", "-Wextra", "-Werror",
                     *includes, str(snippet)],
                    capture_output=True, text=True)
                if run.returncode != 0:
                    failures.append(f"{where}: the C++ block does not compile:\n{run.stderr}")
            elif language in ("sh", "bash"):
                checked["sh"] += 1
                run = subprocess.run(["bash", "-n"], input=text, capture_output=True, text=True)
                if run.returncode != 0:
                    failures.append(f"{where}: the shell block does not parse: {run.stderr}")
                joined = text.replace("\\\n", " ")
                for command in joined.splitlines():
                    for part in re.split(r"\s*(?:&&|\|\||;|\|)\s*", command.strip()):
                        check_command_line(where, part.strip())

print(f"checked {checked['cpp']} C++ blocks, {checked['sh']} shell blocks, "
      f"{checked['afhub']} afhub command lines in {len(pages)} pages")
for failure in failures:
    print("FAIL:", failure)
sys.exit(1 if failures or checked["cpp"] == 0 or checked["afhub"] == 0 else 0)
