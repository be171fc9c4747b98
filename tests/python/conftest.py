"""What the Python tests share: the afhub command line, physics processes started per
test, and the models. run_tests.sh runs them with a hub of their own, inside
tests/support/private_namespaces.sh (ctest does that), so their hub meets no other."""

import os
import pathlib
import subprocess
import sys
import time

import pytest

AFHUB = os.environ.get('AFHUB', 'afhub')
EXAMPLES = pathlib.Path(os.environ.get('AFHUB_EXAMPLE_MODELS', 'examples/models'))
SHARED = pathlib.Path(os.environ.get('AFHUB_SHARED_MODELS', '../shared/ambf_models'))
KUKA = SHARED / 'descriptions/multi-bodies/robots/blender-kuka.yaml'
ECM = SHARED / 'descriptions/multi-bodies/robots/blender-ecm.yaml'


def pytest_configure(config):
    config.addinivalue_line(
        'markers', 'real_time: a timing bound; ctest runs these alone (python_real_time)')


def needs_shared_models():
    return pytest.mark.skipif(not SHARED.is_dir(), reason=(
        f'needs the AMBF model corpus, and {SHARED} does not exist '
        '(AFHUB_SHARED_MODELS; CI has it)'))


def wait_until(condition, timeout_s, what):
    """Polls `condition` until it holds; fails naming `what` when it never does."""
    give_up = time.monotonic() + timeout_s
    while time.monotonic() < give_up:
        value = condition()
        if value:
            return value
        time.sleep(0.01)
    pytest.fail(f'{what}: not within {timeout_s} s')


@pytest.fixture(scope='session', autouse=True)
def hub():
    """The hub run_tests.sh started for the session."""
    if not os.environ.get('AFHUB_PRIVATE_NAMESPACES'):
        pytest.exit('the Python tests use a hub of their own: run them with run_tests.sh inside '
                    'tests/support/private_namespaces.sh (ctest does)', returncode=1)
    if subprocess.run([AFHUB, 'status'], capture_output=True).returncode != 0:
        pytest.exit('no hub is running: run the tests with run_tests.sh', returncode=1)


class Physics:
    """An `afhub run` process; stopped (SIGINT) at the end of the test."""

    def __init__(self, args, log_path):
        self.log_path = log_path
        self.process = subprocess.Popen([AFHUB, 'run', '--no-autostart', *map(str, args)],
                                        stdout=open(log_path, 'w'), stderr=subprocess.STDOUT)

    def log(self):
        return pathlib.Path(self.log_path).read_text()

    def wait_for_body(self, name, timeout_s=20):
        """An afhub.Body for `name` once it publishes. The catalog may still list, for a
        moment, the bodies of a physics an earlier test stopped: a name that finds one of
        those is tried again."""
        import afhub

        def publishing():
            if self.process.poll() is not None:
                pytest.fail(f'afhub run ended with {self.process.returncode}:\n{self.log()}')
            try:
                body = afhub.Body(name)
            except afhub.Error:
                return None
            return body if body.read(wait_s=0.5) is not None else None
        return wait_until(publishing, timeout_s, f'{name} publishes its state\n{self.log()}')

    def wait(self, timeout_s):
        return self.process.wait(timeout=timeout_s)

    def stop(self):
        if self.process.poll() is None:
            self.process.send_signal(2)
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


@pytest.fixture
def physics(tmp_path):
    """physics(*args): starts `afhub run ARGS`, stopped at the end of the test."""
    started = []

    def start(*args):
        started.append(Physics(args, tmp_path / f'run{len(started)}.log'))
        return started[-1]
    yield start
    for process in started:
        process.stop()


def pytest_terminal_summary(terminalreporter):
    # Skips in GoogleTest's form too, so that run.sh counts them and says why.
    for report in terminalreporter.stats.get('skipped', []):
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
        terminalreporter.write_line(reason.removeprefix('Skipped: '))
        terminalreporter.write_line(f'[  SKIPPED ] python.{report.nodeid} (0 ms)')
    sys.stdout.flush()
