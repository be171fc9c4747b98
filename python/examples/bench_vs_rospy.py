#!/usr/bin/env python3
"""The two sides of bench_python.py's first comparison: one Python control iteration
on afhub, and the same through ROS 1 with rospy (AMBF's transport).

- afhub: read a body's newest state and write one position command (bench_iteration.py's
  iteration), with a running simulation.
- rospy: the client publishes the command (std_msgs/Float64MultiArray, one value per
  joint) and waits for the state a second process answers it with (pose, twist and each
  joint's position, velocity and effort: 13 + 3 x joints values), over a rosmaster of
  its own on a free loopback port, TCP_NODELAY both ways. A rospy client keeps the
  newest state its subscriber delivered, so this round trip is the time from a command
  to the state that follows it, and the publish() call alone is timed too.

Run as `bench_vs_rospy.py --echo JOINTS`, it is that second process."""

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


if __name__ == '__main__' and sys.argv[1:2] == ['--echo']:
    echo(int(sys.argv[2]))  # the second process of rospy_figures
