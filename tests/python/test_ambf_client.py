"""AMBF's client on afhub: scripts in the style of AMBF's published Python examples, run
unchanged but for how they are started, against the project's models and the ECM of the
AMBF corpus. The effects are checked in the simulation, from this process, while the
script waits on input()."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import afhub
from ambf_client import Actuator, Client, Sensor
from conftest import AFHUB, ECM, EXAMPLES, needs_shared_models, wait_until

LAUNCH = EXAMPLES / 'launch.yaml'


class Script:
    """A Python script run as its own process; stdin fed a line at a time."""

    def __init__(self, tmp_path, source):
        path = tmp_path / 'script.py'
        path.write_text(textwrap.dedent(source))
        # Unbuffered, so that each line it prints arrives when printed.
        self.process = subprocess.Popen([sys.executable, '-u', str(path)], stdin=subprocess.PIPE,
                                        stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                        text=True, bufsize=1)
        self.output = []

    def read_until(self, marker):
        for line in self.process.stdout:
            self.output.append(line)
            if marker in line:
                return line
        pytest.fail(f'the script ended before "{marker}":\n' + ''.join(self.output))

    def enter(self):
        self.process.stdin.write('\n')
        self.process.stdin.flush()

    def finish(self):
        out, _ = self.process.communicate(timeout=30)
        self.output.append(out)
        assert self.process.returncode == 0, ''.join(self.output)
        return ''.join(self.output)


def held_for(body, check, seconds):
    """True when `check(state)` holds for every state over `seconds` (longer than the
    physics' 0.5 s watchdog: a command not re-sent would be released in it)."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        state = body.wait_next(timeout_s=2.0)
        if not check(state):
            return False
    return True


def joint_0_reaches_and_holds(body, target, what):
    """Joint 0 of `body` reaches `target` (within 0.03) and holds it for a second."""
    wait_until(lambda: abs(body.wait_next().joint_positions[0] - target) < 0.03, 15,
               f'{what}: reached')
    assert held_for(body, lambda s: abs(s.joint_positions[0] - target) < 0.03, 1.0), what


def test_example_script_moves_the_arm_and_the_gripper(physics, tmp_path):
    run = physics('--launch', LAUNCH, '-l', '0,2')
    arm = run.wait_for_body('arm/base')
    palm = run.wait_for_body('gripper/palm')
    script = Script(tmp_path, """
        from ambf_client import Client
        import time

        _client = Client('afhub_test')
        _client.connect()
        print(_client.get_obj_names())
        base = _client.get_obj_handle('arm/base')
        palm = _client.get_obj_handle('/afhub/gripper/palm')
        world = _client.get_world_handle()
        print('handles', base.get_name(), palm.get_name(), world.get_name())
        print('base pos', base.get_pos().x, base.get_pos().y, base.get_pos().z)
        print('base rot', base.get_rot().w, 'rpy', base.get_rpy())
        print('joints', base.get_num_joints(), base.get_joint_names())
        print('sim time', world.get_sim_time())
        # Some joints in position, some in effort.
        base.set_joint_pos(0, 0.5)
        base.set_joint_pos('link1-link2', -0.4)
        base.set_joint_effort(2, 0.0)
        time.sleep(0.5)
        print('STAGE 1: joints commanded; press enter')
        input()
        print('joint 0 at', base.get_joint_pos(0), 'joint 1 at', base.get_joint_pos('link1-link2'))
        z0 = palm.get_pos().z
        start = time.time()
        while time.time() - start < 5.0:
            palm.set_force(0, 0, 4.0)  # AMBF: forces must be refreshed
            time.sleep(0.02)
        print('palm rose by', palm.get_pos().z - z0)
        print('STAGE 2: force done; press enter')
        input()
        _client.clean_up()
        print('DONE')
    """)
    script.read_until('STAGE 1')
    targets = np.array([0.5, -0.4])
    wait_until(lambda: np.all(np.abs(arm.wait_next().joint_positions[:2] - targets) < 0.03), 15,
               'the arm reached the targets the script set')
    # The script waits on input(): its commands are still re-sent, so the joints hold.
    assert held_for(arm, lambda s: np.all(np.abs(s.joint_positions[:2] - targets) < 0.03), 1.5)
    z_before = palm.read().position[2]
    script.enter()
    script.read_until('STAGE 2')
    assert palm.read().position[2] > z_before + 0.1, 'the palm did not rise under the force'
    script.enter()
    output = script.finish()
    assert "'/afhub/arm/base'" in output and 'World' in output
    assert 'joints 7' in output and 'DONE' in output


def test_a_refused_value_leaves_the_command_held_before(physics, tmp_path):
    """A setter given a value that is not finite raises ValueError and sends nothing; the
    handle keeps the command it held, so the next setter works and the client's thread
    re-sends that one. (The NaN used to stay in the handle: every later setter raised, and
    the thread said so 120 times a second.)"""
    run = physics(EXAMPLES / 'arm7.yaml')
    arm = run.wait_for_body('arm/base')
    script = Script(tmp_path, """
        import math
        import numpy
        from ambf_client import Client

        _client = Client('afhub_test')
        _client.connect()
        base = _client.get_obj_handle('arm/base')
        base.set_joint_pos(0, 0.3)
        base.set_multiple_joint_pos([0.3, 0.2, 0.2], numpy.array([1, 2]))  # numpy indices too
        # A value that is no number after a good one: the good one is not kept either.
        for refused in (lambda: base.set_pos(math.nan, 0, 0),
                        lambda: base.set_joint_pos(1, math.inf),
                        lambda: base.set_multiple_joint_pos([0.7, 0.7, 'oops'], [1, 2]),
                        lambda: base.set_multiple_joint_pos([0.7, 0.7, None], [1, 2])):
            try:
                refused()
            except (ValueError, TypeError) as error:
                print('refused:', error)
        for rate in (0, -5, math.nan, 1e-9):
            try:
                _client.set_publish_rate(rate)
            except ValueError as error:
                print('refused:', error)
        base.set_joint_pos(numpy.int64(0), 0.5)
        print('STAGE 1: commanded; press enter')
        input()
        _client.clean_up()
        print('DONE')
    """)
    script.read_until('STAGE 1')
    joint_0_reaches_and_holds(arm, 0.5, 'the target set after the refused ones')
    assert held_for(arm, lambda s: abs(s.joint_positions[1] - 0.2) < 0.03, 1.0), \
        'joint 1 holds the target before the refused values'
    script.enter()
    output = script.finish()
    assert output.count('refused:') == 8 and 'nothing was sent' in output, output
    assert output.count('default_publish_rate takes 10 to 100000 Hz') == 4, output
    assert 'ambf_client: ' not in output, output  # the client's thread sent without a fault


def test_a_command_the_physics_refuses_is_dropped_and_the_one_before_holds(physics, tmp_path):
    """An effort beyond the body's bounds, which only the physics knows: it refuses the
    whole command. The handle re-sent the refused command, the watchdog released the arm
    after 0.5 s, and it fell (a UR5 in the exploratory run). It now goes back to the
    command it held before that setter, which the physics takes: the arm holds."""
    run = physics(EXAMPLES / 'arm7.yaml')
    arm = run.wait_for_body('arm/base')
    script = Script(tmp_path, """
        import time
        from ambf_client import Client

        _client = Client('afhub_test')
        _client.connect()
        base = _client.get_obj_handle('arm/base')
        base.set_joint_pos(1, 0.4)
        time.sleep(1.0)
        base.set_joint_effort(3, 1e9)  # beyond any bound of the arm
        print('STAGE 1: refused; press enter')
        input()
        base.set_joint_pos(0, 0.3)  # setters go on
        print('STAGE 2: commanded; press enter')
        input()
        _client.clean_up()
        print('DONE')
    """)
    script.read_until('STAGE 1')
    wait_until(lambda: abs(arm.wait_next().joint_positions[1] - 0.4) < 0.03, 15,
               'joint 1 reached its target')
    assert held_for(arm, lambda s: abs(s.joint_positions[1] - 0.4) < 0.03, 1.5), \
        'the arm was released after the refused command'
    script.enter()
    script.read_until('STAGE 2')
    joint_0_reaches_and_holds(arm, 0.3, 'a setter after the refused command')
    script.enter()
    output = script.finish()
    assert output.count('goes back to the command it held before the setter') == 1, output
    assert 'joint 3 (link3-link4) effort 1e+09 N m is beyond its bound' in output, output


def test_multiple_joints_take_their_own_entries_of_a_vector_as_in_ambf(physics, tmp_path):
    """set_multiple_joint_pos(q, [2, 4]) with q over all the joints, as AMBF scripts pass it:
    joints 2 and 4 take q[2] and q[4], and the others keep their commands (every joint was
    switched to position control, to q's values). An index past the values raises."""
    run = physics(EXAMPLES / 'arm7.yaml')
    arm = run.wait_for_body('arm/base')
    script = Script(tmp_path, """
        from ambf_client import Client

        _client = Client('afhub_test')
        _client.connect()
        base = _client.get_obj_handle('arm/base')
        base.set_joint_pos(0, 0.5)
        base.set_multiple_joint_pos([1.0, 1.0, 0.3, 1.0, -0.3, 1.0, 1.0], [2, 4])
        try:
            base.set_multiple_joint_pos([0.1], [3])
        except IndexError as error:
            print('refused:', error)
        print('STAGE 1: commanded; press enter')
        input()
        _client.clean_up()
        print('DONE')
    """)
    script.read_until('STAGE 1')
    wanted = {0: 0.5, 2: 0.3, 4: -0.3}
    reached = lambda s: all(abs(s.joint_positions[j] - q) < 0.03 for j, q in wanted.items())
    wait_until(lambda: reached(arm.wait_next()), 15, 'joints 0, 2 and 4 reached 0.5, 0.3, -0.3')
    assert held_for(arm, reached, 1.0), arm.read().joint_positions
    script.enter()
    output = script.finish()
    assert 'refused: joint 3 has no value: 1 values given' in output, output


def test_the_world_handle_is_the_bodies_world_and_none_without_one(physics, tmp_path):
    """No simulation: no world handle (None), as AMBF. A physics run with --namespace: the
    world handle is its world (it was the default namespace's: every call failed, saying
    no simulation ran), also when `afhub synth` (whose world is the default one) came
    first in the catalog, and when it started after connect() (None for good, until
    something read the catalog again). With a second physics in the default namespace,
    the default one's, said (the first started was taken)."""
    script = Script(tmp_path, """
        from ambf_client import Client

        c = Client('afhub_test')
        c.connect()
        print('no simulation:', c.get_world_handle(), 'World' in c.get_obj_names())
        print('STAGE 1: press enter once a physics runs')
        input()
        w = c.get_world_handle()
        print('namespace', repr(w.namespace))
        print('names', c.get_obj_names()[:3])
        step = w.get_sim_step()
        w.reset()
        print('world step', step, 'then', w.get_sim_step(), 'time', w.get_sim_time())
        print('STAGE 2: press enter once a second physics runs')
        input()
        names = c.get_obj_names()
        print('then namespace', repr(c.get_world_handle().namespace), len(names))
        c.clean_up()
        print('DONE')
    """)
    script.read_until('STAGE 1')
    synth = subprocess.Popen([AFHUB, 'synth', '--bodies', '1', '--no-autostart'],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        wait_until(lambda: 'synth/body0' in afhub.bodies(), 10, 'synth listed')
        run = physics(EXAMPLES / 'arm7.yaml', '--namespace', 'copy')
        run.wait_for_body('copy/afhub/arm/base')
        script.enter()
        script.read_until('STAGE 2')
        synth.send_signal(signal.SIGINT)  # its world is the default one
        synth.wait(timeout=10)
        physics(EXAMPLES / 'arm7.yaml').wait_for_body('afhub/arm/base')
        wait_until(lambda: 'afhub/arm/base' in afhub.bodies(), 10, 'the second physics listed')
        script.enter()
        output = script.finish()
    finally:
        synth.send_signal(signal.SIGINT)
        synth.wait(timeout=10)
    assert 'no simulation: None False' in output, output
    assert 'World NAMED OBJECT NOT FOUND: no simulation runs' in output, output
    assert "names ['World', '/synth/body0', '/copy/afhub/arm/" in output, output
    assert "namespace 'copy'" in output, output
    step, after = (int(word) for word in output.split('world step ')[1].split()[:3:2])
    assert step > 0 and after < step, output
    assert "then namespace '' 17" in output, output
    assert output.count("2 simulations run (namespaces 'copy', '')") == 1, output


def test_a_body_named_world_is_that_body_and_wrong_types_raise(physics, tmp_path):
    """A model's body named 'world' (the four-bar's, a URDF's root link) is that body, as
    in AMBF (the World handle came instead, without get_pos); 'World' is the world. A value
    of the wrong type raises TypeError naming it (None was a ValueError, and '1' was read
    as 1 N); values past the last joint are said, as AMBF does."""
    model = tmp_path / 'world_body.yaml'
    model.write_text('bodies: [BODY world, BODY arm]\njoints: [JOINT j]\n'
                     'BODY world:\n  name: world\n  mass: 0\n'
                     'BODY arm:\n  name: arm\n  mass: 1\n  shape: box\n'
                     '  geometry: {x: 0.1, y: 0.1, z: 0.1}\n'
                     'JOINT j:\n  name: j\n  parent: BODY world\n  child: BODY arm\n'
                     '  parent pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: 0, y: 0, z: 1}\n'
                     '  child pivot: {x: 0, y: 0, z: 0}\n  child axis: {x: 0, y: 0, z: 1}\n'
                     '  type: revolute\n')
    physics(model).wait_for_body('arm')
    script = Script(tmp_path, """
        from ambf_client import Client
        c = Client()
        c.connect()
        world = c.get_obj_handle('world')
        assert world is not c.get_world_handle() and isinstance(world.get_pos().z, float), world
        assert c.get_obj_handle('World') is c.get_world_handle()
        for call in (lambda: world.set_joint_pos(0, None), lambda: world.set_force('1', 0, 0),
                     lambda: world.set_pos(0, True, 0)):
            try:
                call()
                print('accepted')
            except TypeError as error:
                print('refused:', error)
        world.set_multiple_joint_pos([0.1, 0.2])
        print('DONE')
    """)
    output = script.finish()
    assert output.count('refused:') == 3 and 'accepted' not in output, output
    assert "refused: a joint value is a real number, not None" in output, output
    assert "refused: x is a real number, not '1'" in output, output
    assert "refused: y is a real number, not True" in output, output
    assert 'Requested Joint index is out of range with joints 1: 2 values given' in output, output
    assert 'DONE' in output, output


def test_names_handles_and_unsupported_calls(physics, tmp_path):
    run = physics(EXAMPLES / 'arm7.yaml')
    run.wait_for_body('arm/base')
    script = Script(tmp_path, """
        from ambf_client import Client
        c = Client()
        c.connect()
        names = c.get_obj_names()
        assert '/afhub/arm/base' in names and 'World' in names, names
        assert c.get_common_namespace() == '/afhub/arm/', c.get_common_namespace()
        a = c.get_obj_handle('/afhub/arm/base')
        assert c.get_obj_handle('arm/base') is a and c.get_obj_handle('base') is a
        assert c.get_obj_handle('afhub/arm/link7').get_name() == '/afhub/arm/link7'
        assert c.get_obj_handle('World') is c.get_world_handle()
        assert c.get_obj_handle('world') is c.get_world_handle()  # no body is named so
        assert c.get_obj_handle('no_such_body') is None
        assert c.get_obj_handle('link') is None  # seven match: said, naming them
        assert a.get_joint_idx_from_name('link2-link3') == 2
        assert a.get_joint_pos(99) is None
        assert len(c.get_obj_pose('arm/base')) == 6
        assert a.get_children_names() == ['link1'], a.get_children_names()
        assert a.get_num_of_children() == 1 and a.get_parent_name() == 'mount'
        link7 = c.get_obj_handle('arm/link7')
        assert link7.get_children_names() == [] and link7.get_parent_name() == 'link6'
        try:
            a.get_msg_header()
            raise SystemExit('get_msg_header did not raise')
        except NotImplementedError as error:
            print('unsupported:', error)
        w = c.get_world_handle()
        w.enable_throttling(True)  # paused: the clock moves only on update()
        step = w.get_sim_step()
        w.set_num_step_skips(5)
        w.update()
        assert w.get_sim_step() == step + 5, (step, w.get_sim_step())
        w.enable_throttling(False)
        w.reset()
        c.clean_up()
        print('OK')
    """)
    output = script.finish()
    assert 'unsupported: get_msg_header' in output and 'OK' in output
    assert 'no_such_body NAMED OBJECT NOT FOUND' in output
    assert 'link NAMED OBJECT NOT FOUND: 7 objects match it: /afhub/arm/link1' in output, output


def test_misuse_is_refused_and_throttling_ends_with_the_script(physics, tmp_path):
    """Found by fault injection: a handle got before connect(), or kept after clean_up(),
    took setters that were sent once and never again (the watchdog let the arm fall); a
    throttled script that ended left the world paused for good; three values to set_rot
    became a quaternion (x, y, z, 1); a step skip of 0.5 became 0; a joint value True or
    '0.5' was read as a number."""
    run = physics(EXAMPLES / 'arm7.yaml')
    run.wait_for_body('arm/base')
    script = Script(tmp_path, """
        from ambf_client import Client
        c = Client()
        for call, error in ((lambda: c.get_obj_handle('arm/base'), RuntimeError),
                            (lambda: c.get_world_handle(), RuntimeError),
                            (lambda: c.get_obj_handle(None), TypeError)):
            try:
                call()
                raise SystemExit('not refused')
            except error as refused:
                print('refused:', refused)
        c.connect()
        a = c.get_obj_handle('arm/base')
        try:
            a.set_rot([0, 0, 1])
            raise SystemExit('set_rot took three values')
        except ValueError as refused:
            print('refused:', refused)
        for value in (True, '0.5', None):  # float() read the first two as 1 and 0.5
            try:
                a.set_joint_pos(0, value)
                raise SystemExit(f'set_joint_pos took {value!r}')
            except TypeError:
                pass
        w = c.get_world_handle()
        for skips in (0.5, 2.5, '5', True, 0, 101):
            try:
                w.set_num_step_skips(skips)
                raise SystemExit(f'set_num_step_skips took {skips!r}')
            except ValueError:
                pass
        c.clean_up()
        for call in (lambda: a.set_joint_pos(0, 0.2), lambda: w.enable_throttling(True)):
            try:
                call()
                raise SystemExit('a cleaned-up handle took a setter')
            except RuntimeError as refused:
                print('refused:', refused)
        c.connect()
        w = c.get_world_handle()
        w.enable_throttling(True)
        w.update()
        print('THROTTLED', flush=True)
        raise SystemExit(0)  # ends throttled, without clean_up()
    """)
    script.read_until('THROTTLED')
    output = script.finish()
    assert output.count('refused:') == 6, output
    assert 'the client is not connected: call connect() first' in output
    assert 'a quaternion takes four values' in output
    assert "this handle's client was cleaned up" in output
    world = afhub.World()
    step = world.sim_step()
    wait_until(lambda: world.sim_step() > step + 100, 5, 'the world running on after the script')
    assert not world.state()['paused']


def test_a_throttled_script_killed_lets_the_world_run_on(physics, tmp_path):
    """A throttling client's pause is held: while the script lives (idle between updates,
    its publisher thread renewing the hold) the world stays paused; stopped (SIGSTOP), the
    hold lapses and the world runs on, and the script's next update() pauses it again;
    SIGKILLed, with no atexit to resume it, the world runs on once more, and the physics
    says so. Before, a killed script left the world paused for good."""
    run = physics(EXAMPLES / 'arm7.yaml')
    run.wait_for_body('arm/base')
    script = Script(tmp_path, """
        import time
        from ambf_client import Client
        c = Client()
        c.connect()
        w = c.get_world_handle()
        w.enable_throttling(True)
        w.update()
        print('THROTTLED', flush=True)
        input()
        w.update()  # the world ran on while the script was stopped
        print('STEPPED', flush=True)
        time.sleep(60)
    """)
    script.read_until('THROTTLED')
    world = afhub.World()
    step = world.sim_step()
    idle_until = time.monotonic() + 2.0  # twice the hold
    while time.monotonic() < idle_until:
        assert world.state()['paused'] and world.sim_step() == step, 'the hold lapsed too soon'
        time.sleep(0.05)

    def runs_on(what):
        start = world.sim_step()
        wait_until(lambda: world.sim_step() > start + 100, 10, what)
        assert not world.state()['paused']

    script.process.send_signal(signal.SIGSTOP)
    runs_on('the world running on while the script is stopped')
    script.process.send_signal(signal.SIGCONT)
    script.enter()
    script.read_until('STEPPED')
    assert world.state()['paused'], 'the update after the lapse did not pause the world again'
    script.process.kill()
    script.process.wait(timeout=10)
    runs_on('the world running on after the kill')
    wait_until(lambda: run.log().count('lapsed, nothing from it for 1000 ms') == 2, 5,
               'the physics saying twice why it runs on')


def test_two_throttling_scripts_hold_one_pause_and_a_users_pause_outlives_them(physics, tmp_path):
    """Two throttling scripts hold the world's pause together: the second one SIGKILLed,
    the first one's hold keeps the world paused (the last holder alone held it, and the
    world ran on while the first one still renewed). A script that ends cleanly releases
    its own hold only: a pause the user took meanwhile stays (it resumed the world)."""
    run = physics(EXAMPLES / 'arm7.yaml')
    run.wait_for_body('arm/base')
    source = """
        from ambf_client import Client
        c = Client()
        c.connect()
        w = c.get_world_handle()
        w.enable_throttling(True)
        w.update()
        print('THROTTLED', flush=True)
        input()
    """
    (tmp_path / 'a').mkdir()
    (tmp_path / 'b').mkdir()
    first, second = Script(tmp_path / 'a', source), Script(tmp_path / 'b', source)
    first.read_until('THROTTLED')
    second.read_until('THROTTLED')
    world = afhub.World()
    assert world.state()['pause_held']
    second.process.kill()
    second.process.wait(timeout=10)
    step = world.sim_step()
    idle_until = time.monotonic() + 2.5  # past the killed one's hold
    while time.monotonic() < idle_until:
        assert world.state()['paused'] and world.sim_step() == step, \
            'the world ran on while a throttling script still held it'
        time.sleep(0.05)
    assert world.state()['paused_by_pid'] == first.process.pid
    assert 'lapsed' not in run.log()
    assert world.pause().startswith('already paused')  # the user's own, plain
    first.enter()
    assert first.process.wait(timeout=10) == 0
    time.sleep(0.5)
    state = world.state()
    assert state['paused'] and state['paused_by_pid'] == os.getpid() and not state['pause_held']
    assert world.sim_step() == step, 'the script ending resumed the user\'s pause'


@needs_shared_models()
def test_ecm_by_ambf_names(physics, tmp_path):
    run = physics(ECM)
    ecm = run.wait_for_body('ecm/baselink')
    script = Script(tmp_path, """
        from ambf_client import Client
        c = Client('ecm_test')
        c.connect()
        print(c.get_obj_names())
        b = c.get_obj_handle('ecm/baselink')
        assert b is c.get_obj_handle('/ambf/env/ecm/baselink')
        print('joints', b.get_num_joints(), b.get_joint_names())
        b.set_joint_pos(0, 0.3)
        print('STAGE 1')
        input()
        c.clean_up()
    """)
    script.read_until('STAGE 1')
    joint_0_reaches_and_holds(ecm, 0.3, 'the ECM joint 0 at 0.3')
    script.enter()
    output = script.finish()
    assert "'/ambf/env/ecm/baselink'" in output


def write_parts_model(tmp_path):
    """`afhub run` arguments: a model with a proximity sensor and a constraint actuator, and
    a world with a camera and a light. The probe's ray looks along +x, 2 m; the block
    (static: a pose command moves it) starts out of it. The gripper's actuator is at its
    origin, inside the ball resting on the table under it."""
    (tmp_path / 'parts.yaml').write_text(textwrap.dedent("""\
        namespace: /afhub/parts/
        bodies: [BODY probe, BODY block, BODY gripper, BODY ball, BODY table]
        sensors: [SENSOR range]
        actuators: [ACTUATOR grip]
        BODY probe:
          name: probe
          mass: 0
          shape: sphere
          geometry: {radius: 0.05}
          location: {position: {x: 0, y: -2, z: 0}}
        BODY block:
          name: block
          mass: 0
          shape: box
          geometry: {x: 0.2, y: 0.2, z: 0.2}
          location: {position: {x: 1, y: 2, z: 0}}
        BODY gripper:
          name: gripper
          mass: 0
        BODY ball:
          name: ball
          mass: 1
          shape: sphere
          geometry: {radius: 0.05}
          location: {position: {x: 0, y: 0, z: -0.045}}
        BODY table:
          name: table
          mass: 0
          shape: box
          geometry: {x: 1, y: 1, z: 0.1}
          location: {position: {x: 0, y: 0, z: -0.145}}
        SENSOR range:
          name: range
          type: Proximity
          parent: BODY probe
          range: 2.0
          array:
          - {offset: {x: 0, y: 0, z: 0}, direction: {x: 1, y: 0, z: 0}}
        ACTUATOR grip:
          name: grip
          type: Constraint
          parent: BODY gripper
          max impulse: 10
          tau: 1
        """))
    (tmp_path / 'world.yaml').write_text(textwrap.dedent("""\
        namespace: /afhub/parts/
        gravity: {x: 0.0, y: 0.0, z: -9.81}
        lights: [light_top]
        cameras: [camera_front]
        light_top:
          name: top
          location: {x: 0, y: 0, z: 3}
          direction: {x: 0, y: 0, z: -1}
        camera_front:
          name: front
          location: {x: 3, y: 0, z: 1}
          look at: {x: 0, y: 0, z: 0}
          up: {x: 0, y: 0, z: 1}
        """))
    return tmp_path / 'parts.yaml', '--world', tmp_path / 'world.yaml'


def test_proximity_sensor_sees_a_body_moved_into_its_ray(physics, tmp_path):
    run = physics(*write_parts_model(tmp_path))
    run.wait_for_body('parts/probe')
    c = Client('sensor_test')
    c.connect()
    try:
        assert '/afhub/parts/range' in c.get_obj_names()
        sensor = c.get_obj_handle('range')
        assert isinstance(sensor, Sensor) and sensor is c.get_obj_handle('/afhub/parts/range')
        assert sensor.get_count() == 1 and sensor.get_parent_name() == 'probe'
        assert sensor.get_range(0) == pytest.approx(2.0)
        assert sensor.is_triggered(0) is False and sensor.get_measurement(0) == 0.0
        assert sensor.get_measurement(1) is None  # past its elements, as AMBF
        c.get_obj_handle('parts/block').set_pos(1.0, -2.0, 0.0)  # into the ray
        wait_until(lambda: sensor.is_triggered(0), 10, 'the sensor sees the block')
        # The block's near face is 0.9 m along the 2 m ray.
        assert sensor.get_distance(0) == pytest.approx(0.9, abs=0.005)
        assert sensor.get_measurement(0) == pytest.approx(1.0 - 0.9 / 2.0, abs=0.005)
        with pytest.raises(NotImplementedError, match='get_sensed_object'):
            sensor.get_sensed_object(0)
        camera = c.get_obj_handle('front')
        with pytest.raises(NotImplementedError, match='^get_pos: .*front is a camera'):
            camera.get_pos()
        with pytest.raises(NotImplementedError, match='^set_intensity: .*top is a light'):
            c.get_obj_handle('top').set_intensity(0.5)
    finally:
        c.clean_up()


def test_actuator_holds_the_touching_body_and_lets_go(physics, tmp_path):
    run = physics(*write_parts_model(tmp_path))
    ball = run.wait_for_body('parts/ball')
    c = Client('actuator_test')
    c.connect()
    try:
        grip = c.get_obj_handle('grip')
        assert isinstance(grip, Actuator) and grip.get_parent_name() == 'gripper'
        gripper = c.get_obj_handle('parts/gripper')
        assert ball.wait_next().position[2] < 0.0  # on the table
        grip.actuate('ball')
        gripper.set_pos(0.0, 0.0, 0.5)  # the gripper jumps 0.5 m up: the ball must follow
        wait_until(lambda: ball.wait_next().position[2] > 0.35, 10,
                   'the held ball followed the gripper up')
        # Held for longer than the watchdog: the client re-sends the actuator's flag.
        assert held_for(ball, lambda s: s.position[2] > 0.35, 1.0)
        grip.deactuate()
        wait_until(lambda: ball.wait_next().position[2] < 0.0, 10,
                   'the released ball fell back to the table')
        with pytest.raises(NotImplementedError, match='pose'):
            grip.actuate('ball', pose=[0, 0, 0, 0, 0, 0])
    finally:
        c.clean_up()
