#!/usr/bin/env python3
"""One Python control iteration on afhub beside the same through ROS 1 with rospy (AMBF's
transport), in the same run; prints p50 and p99 in microseconds, and the load average.

- afhub: read a body's newest state and write one position command (bench_iteration.py's
  iteration), with a running simulation:
      build/release/bin/afhub run examples/models/arm7.yaml &
- rospy: the client publishes the command (std_msgs/Float64MultiArray, one value per
  joint) and waits for the state a second process answers it with (pose, twist and each
  joint's position, velocity and effort: 13 + 3 x joints values), over a rosmaster of
  its own on a free loopback port, TCP_NODELAY both ways. A rospy client keeps the
  newest state its subscriber delivered, so this round trip is the time from a command
  to the state that follows it, and the publish() call alone is timed too.

    PYTHONPATH=$PWD/build/release/python python3 python/examples/bench_vs_rospy.py arm/base

Needs Debian's python3-rospy and python3-rosmaster (run.sh installs them)."""

import os
import socket
import subprocess
import sys
import tempfile
import threading
import time

from bench_iteration import timed

COMMAND_TOPIC = '/afhub_bench/command'
STATE_TOPIC = '/afhub_bench/state'


def free_port():
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        return probe.getsockname()[1]


def echo(joints):
    """The second process: answers each command with a state, carrying the command's
    sequence number (its first value) first."""
    import rospy
    from std_msgs.msg import Float64MultiArray

    rospy.init_node('afhub_bench_echo', disable_signals=True, disable_rosout=True)
    state = Float64MultiArray(data=[0.0] * (13 + 3 * joints))
    publisher = rospy.Publisher(STATE_TOPIC, Float64MultiArray, queue_size=1, tcp_nodelay=True)

    def answer(command):
        state.data[0] = command.data[0]
        publisher.publish(state)
    rospy.Subscriber(COMMAND_TOPIC, Float64MultiArray, answer, tcp_nodelay=True)
    rospy.spin()


class RospyClient:
    """The client side: publish() a command, wait for the state answering it."""

    def __init__(self, joints):
        import rospy
        from std_msgs.msg import Float64MultiArray

        rospy.init_node('afhub_bench_client', disable_signals=True, disable_rosout=True)
        self.command = Float64MultiArray(data=[0.0] * joints)
        self.publisher = rospy.Publisher(COMMAND_TOPIC, Float64MultiArray, queue_size=1,
                                         tcp_nodelay=True)
        self.answered = threading.Condition()
        self.latest = -1.0
        rospy.Subscriber(STATE_TOPIC, Float64MultiArray, self._on_state, tcp_nodelay=True)
        self.sequence = 0.0

    def _on_state(self, state):
        with self.answered:
            self.latest = state.data[0]
            self.answered.notify()

    def round_trip(self, timeout_s=1.0):
        self.sequence += 1
        self.command.data[0] = self.sequence
        with self.answered:
            self.publisher.publish(self.command)
            return self.answered.wait_for(lambda: self.latest == self.sequence, timeout_s)

    def publish_only(self):
        self.publisher.publish(self.command)


def rospy_figures(joints, count):
    """p50/p99 of the rospy round trip and of publish() alone, over a rosmaster and an
    echo process of its own (stopped at the end)."""
    env = dict(os.environ, ROS_MASTER_URI=f'http://127.0.0.1:{free_port()}',
               ROS_HOSTNAME='127.0.0.1', ROS_HOME=tempfile.mkdtemp(prefix='afhub-bench-ros-'))
    os.environ.update(env)
    port = env['ROS_MASTER_URI'].rsplit(':', 1)[1]
    children = [subprocess.Popen(['rosmaster', '--core', '-p', port], env=env,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        import rosgraph
        give_up = time.monotonic() + 10
        while not rosgraph.Master('/afhub_bench').is_online():
            if time.monotonic() > give_up:
                raise SystemExit(f'no rosmaster at {env["ROS_MASTER_URI"]} after 10 s')
            time.sleep(0.05)
        children.append(subprocess.Popen([sys.executable, __file__, '--echo', str(joints)],
                                         env=env))
        client = RospyClient(joints)
        give_up = time.monotonic() + 20
        while not client.round_trip(timeout_s=0.1):  # until both connections are up
            if time.monotonic() > give_up:
                raise SystemExit('the rospy echo process did not answer in 20 s')

        def round_trip():
            if not client.round_trip():
                raise SystemExit('a rospy command got no answer within 1 s')
        timed(round_trip, count // 10)  # warm up
        return timed(round_trip, count), timed(client.publish_only, count)
    finally:
        for child in reversed(children):
            child.terminate()
            child.wait()


def afhub_figures(name, count):
    import afhub

    body = afhub.Body(name, wait_s=10)
    joints = len(body.read(wait_s=10).joint_positions)

    def iteration():
        state = body.read()
        body.set_joint_positions(state.joint_positions)
    timed(iteration, count // 10)  # warm up
    return joints, timed(iteration, count)


def main():
    if sys.argv[1:2] == ['--echo']:
        echo(int(sys.argv[2]))
        return
    name = sys.argv[1] if len(sys.argv) > 1 else 'arm/base'
    count = int(sys.argv[2]) if len(sys.argv) > 2 else 10_000
    joints, (afhub_p50, afhub_p99) = afhub_figures(name, count)
    (trip_p50, trip_p99), (publish_p50, publish_p99) = rospy_figures(joints, count)
    load = ', '.join(f'{value:.1f}' for value in os.getloadavg())
    print(f'{count} iterations each, {joints} joints, load average {load}')
    print(f'afhub read + command      p50 {afhub_p50:8.2f} us   p99 {afhub_p99:8.2f} us')
    print(f'rospy command -> state    p50 {trip_p50:8.2f} us   p99 {trip_p99:8.2f} us')
    print(f'rospy publish() alone     p50 {publish_p50:8.2f} us   p99 {publish_p99:8.2f} us')
    print(f'rospy round trip / afhub iteration: {trip_p50 / afhub_p50:.0f}x at p50, '
          f'{trip_p99 / afhub_p99:.0f}x at p99')


if __name__ == '__main__':
    main()
