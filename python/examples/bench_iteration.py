#!/usr/bin/env python3
"""One Python control iteration on afhub: read a body's newest state and write one
command, timed N times; prints p50 and p99 in microseconds. Needs a running simulation:

    build/release/bin/afhub run examples/models/arm7.yaml &
    PYTHONPATH=$PWD/build/release/python python3 python/examples/bench_iteration.py arm/base

It also times the read alone, and a call that looks at the sample in place without
copying it (Body.check_refused), so that the cost of the one copy a read makes shows."""

import math
import sys
import time

import afhub


def percentiles(samples_ns):
    """p50 and p99 in us by afhub's one rule (rt/percentile.hpp): nearest rank, the
    smallest sample with at least ceil(q * N) samples at or below it."""
    samples = sorted(samples_ns)

    def quantile(q):
        return samples[max(1, math.ceil(q * len(samples))) - 1] / 1000
    return quantile(0.50), quantile(0.99)


def timed(function, count):
    samples = []
    clock = time.perf_counter_ns
    for _ in range(count):
        start = clock()
        function()
        samples.append(clock() - start)
    return percentiles(samples)


def main():
    name = sys.argv[1] if len(sys.argv) > 1 else 'arm/base'
    count = int(sys.argv[2]) if len(sys.argv) > 2 else 100_000
    body = afhub.Body(name, wait_s=10)
    first = body.read(wait_s=10)
    targets = first.joint_positions.copy()

    def iteration():
        state = body.read()
        body.set_joint_positions(state.joint_positions)

    for label, function in (('read + command', iteration),
                            ('read (one copy)', body.read),
                            ('in place, no copy', body.check_refused),
                            ('command', lambda: body.set_joint_positions(targets))):
        timed(function, count // 10)  # warm up
        p50, p99 = timed(function, count)
        print(f'{label:20s} p50 {p50:6.2f} us   p99 {p99:6.2f} us   ({count} iterations, '
              f'{len(first.joint_positions)} joints)')


if __name__ == '__main__':
    main()
