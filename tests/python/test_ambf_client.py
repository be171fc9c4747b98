"""AMBF's client on afhub: scripts in the style of AMBF's published Python examples, run
unchanged but for how they are started, against the project's models and the ECM of the
AMBF corpus. The effects are checked in the simulation, from this process, while the
script waits on input()."""

import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import afhub
from conftest import ECM, EXAMPLES, needs_shared_models, wait_until

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
        assert c.get_obj_handle('no_such_body') is None
        assert a.get_joint_idx_from_name('link2-link3') == 2
        assert a.get_joint_pos(99) is None
        assert len(c.get_obj_pose('arm/base')) == 6
        try:
            a.get_children_names()
            raise SystemExit('get_children_names did not raise')
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
    assert 'unsupported: get_children_names' in output and 'OK' in output
    assert 'no_such_body NAMED OBJECT NOT FOUND' in output


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
    wait_until(lambda: abs(ecm.wait_next().joint_positions[0] - 0.3) < 0.03, 15,
               'the ECM joint 0 reached 0.3')
    assert held_for(ecm, lambda s: abs(s.joint_positions[0] - 0.3) < 0.03, 1.0)
    script.enter()
    output = script.finish()
    assert "'/ambf/env/ecm/baselink'" in output
