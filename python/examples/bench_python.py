#!/usr/bin/env python3
"""Python on afhub, measured in one run:

1. one control iteration (read a body's newest state, write one position command)
   beside the same round trip through ROS 1 with rospy, AMBF's transport
   (bench_vs_rospy.py);
2. a 1 kHz afhub.Loop's wake-up latency beside a C++ loop's (`afhub ctl hold` on the
   same body), both running at once, as their published loop statistics give them.

Prints both tables; --plot OUT.png draws them with gnuplot (Debian's gnuplot-nox).

    build/release/bin/afhub run examples/models/arm7.yaml &
    PYTHONPATH=$PWD/build/release/python AFHUB=build/release/bin/afhub \\
        python3 python/examples/bench_python.py --plot docs/python_bench.png

Needs python3-rospy and python3-rosmaster (run.sh installs them)."""

import argparse
import os
import subprocess
import sys
import tempfile
import time

from bench_vs_rospy import afhub_figures, rospy_figures


def loop_figures(name, seconds):
    """Wake-up latency percentiles (us) of a C++ and a Python 1 kHz loop run together."""
    import afhub

    body = afhub.Body(name, wait_s=10)
    hold = subprocess.Popen([os.environ.get('AFHUB', 'afhub'), 'ctl', 'hold', name],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        give_up = time.monotonic() + 10
        while not [s for s in afhub.loop_stats() if s['pid'] == hold.pid]:
            if hold.poll() is not None or time.monotonic() > give_up:
                raise SystemExit(f'afhub ctl hold {name} did not run: {hold.stderr.read()}')
            time.sleep(0.05)
        python = afhub.Loop(1000, lambda state: None, body=body, name='python bench')
        python_report = python.run(seconds=seconds)
        cpp = [s for s in afhub.loop_stats() if s['pid'] == hold.pid][0]
    finally:
        hold.terminate()
        hold.wait()
    return {'C++ ctl hold': cpp['wake_latency'], 'Python afhub.Loop': python_report['wake_latency']}


def plot(path, iteration, loops):
    """Two panels, log scale: the iteration beside rospy, and the two loops' wake-ups."""
    with tempfile.TemporaryDirectory() as tmp:
        with open(f'{tmp}/iteration.dat', 'w') as f:
            for label, (p50, p99) in iteration.items():
                f.write(f'"{label}" {p50} {p99}\n')
        with open(f'{tmp}/loops.dat', 'w') as f:
            for label, latency in loops.items():
                f.write(f'"{label}" {latency["p50_us"]} {latency["p99_us"]} '
                        f'{latency["p999_us"]}\n')
        script = '\n'.join([
            'set terminal pngcairo size 1200,480 font "sans,10"',
            f"set output '{path}'",
            'set multiplot layout 1,2',
            'set style data histograms',
            'set style histogram clustered gap 1',
            'set style fill solid 0.8 border -1',
            'set logscale y',
            'set grid ytics',
            'set ylabel "microseconds (log scale)"',
            'set key top left',
            'set title "One iteration from Python: read a state, write a command"',
            'set xrange [-0.6:2.6]',
            f"plot '{tmp}/iteration.dat' using 2:xtic(1) title 'p50', '' using 3 title 'p99'",
            'set title "1 kHz loops run together: wake-up latency"',
            'set xrange [-0.6:1.6]',
            f"plot '{tmp}/loops.dat' using 2:xtic(1) title 'p50', '' using 3 title 'p99', "
            "'' using 4 title 'p99.9'",
            'unset multiplot',
        ])
        subprocess.run(['gnuplot'], input=script, text=True, check=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('body', nargs='?', default='arm/base')
    parser.add_argument('--count', type=int, default=10_000, help='iterations of each call')
    parser.add_argument('--seconds', type=float, default=10, help='how long the loops run')
    parser.add_argument('--plot', metavar='OUT.png', help='draw the figures into this file')
    args = parser.parse_args()
    # The loops first: rospy leaves threads of its own in this process, which would
    # take the GIL from the Python loop.
    loops = loop_figures(args.body, args.seconds)
    joints, (afhub_p50, afhub_p99) = afhub_figures(args.body, args.count)
    (trip_p50, trip_p99), (publish_p50, publish_p99) = rospy_figures(joints, args.count)
    load = ', '.join(f'{value:.1f}' for value in os.getloadavg())
    print(f'{args.count} iterations each, {joints} joints; loops for {args.seconds:g} s; '
          f'load average {load}')
    # (rospy's round trip: its command, and the state a second process answers it with.)
    iteration = {'afhub read + command': (afhub_p50, afhub_p99),
                 'rospy round trip': (trip_p50, trip_p99),
                 'rospy publish()': (publish_p50, publish_p99)}
    for label, (p50, p99) in iteration.items():
        print(f'{label:24s} p50 {p50:8.2f} us   p99 {p99:8.2f} us')
    print(f'rospy round trip / afhub iteration: {trip_p50 / afhub_p50:.0f}x at p50, '
          f'{trip_p99 / afhub_p99:.0f}x at p99')
    for label, latency in loops.items():
        print(f'{label:24s} wake-up p50 {latency["p50_us"]:6.0f} us   p99 '
              f'{latency["p99_us"]:6.0f} us   p99.9 {latency["p999_us"]:6.0f} us   '
              f'max {latency["max_us"]:6.0f} us')
    cpp, python = loops['C++ ctl hold'], loops['Python afhub.Loop']
    print(f'Python / C++ wake-up p99: {python["p99_us"] / cpp["p99_us"]:.2f}')
    if args.plot:
        plot(args.plot, iteration, loops)
        print(f'plotted: {args.plot}')


if __name__ == '__main__':
    sys.exit(main())
