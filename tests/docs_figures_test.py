#!/usr/bin/env python3
"""The bench's tables in docs/performance.md are the committed runs' figures: each is
exactly what docs/bench_tables.py makes of the JSON beside it, so a table cannot drift
from its data, nor the data be replaced without the table.

    docs_figures_test.py SOURCE_DIR
"""
import pathlib
import subprocess
import sys

source = pathlib.Path(sys.argv[1])
page = (source / "docs" / "performance.md").read_text()
made_from = [
    ["docs/bench_touch.json"],
    ["docs/bench.json"],
    ["docs/bench.json", "docs/bench_touch.json", "--loop"],
]
failures = []
checked = 0
for args in made_from:
    tables = subprocess.run([sys.executable, str(source / "docs" / "bench_tables.py"), *args],
                            cwd=source, capture_output=True, text=True, check=True).stdout
    for table in tables.strip().split("\n\n"):
        checked += 1
        if table not in page:
            wrong = [line for line in table.splitlines() if line not in page]
            failures.append(f"docs/performance.md lacks the table `bench_tables.py "
                            f"{' '.join(args)}` makes; its rows not on the page:\n  " +
                            "\n  ".join(wrong))
print(f"checked {checked} tables of the bench's runs against docs/performance.md")
for failure in failures:
    print("FAIL:", failure)
sys.exit(1 if failures or checked == 0 else 0)
