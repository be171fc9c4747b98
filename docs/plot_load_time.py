#!/usr/bin/env python3
"""Plots scene_benchmark's load times against the number of robots (Fig. 10).

    build/release/bin/scene_benchmark --benchmark_out=load.json --benchmark_out_format=json
    docs/plot_load_time.py load.json docs/load_time.png

Reads Google Benchmark's JSON (standard library only) and draws with gnuplot
(Debian's gnuplot-nox, which `afhub bench --plot` uses too)."""
import json
import subprocess
import sys
import tempfile

SERIES = {
    "BM_LoadExampleRobots": "example arm, RCM arm and gripper in turn",
    "BM_LoadEcms": "da Vinci ECM (AMBF corpus) N times",
}


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_load_time.py BENCHMARK.json OUT.png")
    with open(sys.argv[1]) as f:
        runs = json.load(f)["benchmarks"]
    points = {name: [] for name in SERIES}
    for run in runs:
        name = run["name"].split("/")[0]
        if name in points and run.get("run_type", "iteration") == "iteration" and "error_occurred" not in run:
            ms = run["cpu_time"] if run["time_unit"] == "ms" else run["cpu_time"] / 1e6
            points[name].append((int(run["robots"]), ms))
    with tempfile.TemporaryDirectory() as tmp:
        plots = []
        for name, title in SERIES.items():
            if not points[name]:
                continue
            data = f"{tmp}/{name}.dat"
            with open(data, "w") as f:
                for robots, ms in sorted(points[name]):
                    f.write(f"{robots} {ms}\n")
            plots.append(f"'{data}' using 1:2 with linespoints lw 2 title '{title}'")
        if not plots:
            sys.exit("no load-time results in " + sys.argv[1])
        script = "\n".join([
            "set terminal pngcairo size 800,500",
            f"set output '{sys.argv[2]}'",
            "set title 'afhub: time to load N robots into one world (parse, meshes, Bullet world)'",
            "set xlabel 'robots loaded'",
            "set ylabel 'load time, CPU (ms)'",
            "set key top left",
            "set grid",
            "set yrange [0:*]",
            "plot " + ", ".join(plots),
        ])
        subprocess.run(["gnuplot"], input=script, text=True, check=True)


if __name__ == "__main__":
    main()
