"""AMBF's ``Client`` on afhub: finds the simulated bodies in afhub's catalog instead of
ROS topics, hands out handles to them, and re-sends every handle's command at the
publish rate from a background thread."""

import os
import sys
import threading
import time

import afhub

from .rigid_body import RigidBody
from .world import World


class Client:
    def __init__(self, client_name='ambf_client'):
        self._client_name = client_name
        self._objects = {}  # AMBF name ('/ambf/env/ecm/baselink') -> handle, once asked for
        self._names = []  # AMBF names of the live bodies, from the catalog
        self._common_namespace = ''
        self._world = None
        self._rate_hz = 120.0
        self._thread = None
        self._running = False

    # ----- connecting -----
    def connect(self, default_publish_rate=120):
        """Joins the hub, reads the catalog and starts the thread re-sending commands."""
        afhub.connect(wait_s=float(os.environ.get('AFHUB_WAIT', '0')))
        self._rate_hz = float(default_publish_rate)
        self._read_catalog()
        self.start()

    def create_objs_from_rostopics(self, publish_rate):
        self._rate_hz = float(publish_rate)
        self._read_catalog()

    def start(self):
        if self._thread is None:
            self._running = True
            self._thread = threading.Thread(target=self._run_publishers, daemon=True,
                                            name=f'{self._client_name} publisher')
            self._thread.start()

    def refresh(self):
        self.clean_up()
        self.connect(self._rate_hz)

    def set_publish_rate(self, rate):
        self._rate_hz = float(rate)

    def _read_catalog(self):
        self._names = ['/' + channel for channel in afhub.bodies()]
        self._common_namespace = os.path.commonprefix(self._names) if self._names else ''
        if self._common_namespace and not self._common_namespace.endswith('/'):
            self._common_namespace = self._common_namespace[:self._common_namespace.rfind('/') + 1]

    # ----- names and handles -----
    def get_common_namespace(self):
        return self._common_namespace

    def get_obj_names(self):
        """Every live body's AMBF name ('/ambf/env/ecm/baselink'), and 'World' when a
        simulation runs."""
        self._read_catalog()
        return (['World'] if self._names else []) + list(self._names)

    def get_world_handle(self):
        if self._world is None:
            self._world = World('World')
            self._world.set_active()
        return self._world

    def _find(self, a_name):
        names = self._names
        for candidate in (a_name, '/' + a_name.lstrip('/')):
            if candidate in names:
                return candidate, None
        try:  # afhub's rule: a unique suffix after a '/'
            return '/' + afhub.resolve(a_name.lstrip('/')), None
        except afhub.Error as error:
            message = str(error)
        matches = [name for name in names if a_name in name]  # AMBF's rule: a substring
        if len(matches) == 1:
            return matches[0], None
        return None, message

    def get_obj_handle(self, a_name):
        """A handle to the body named a_name: its full AMBF name ('/ambf/env/ecm/baselink'),
        a part of it after a '/' ('ecm/baselink', 'baselink'), any part that only one body's
        name holds, or 'World'. None when none or several match, saying which (as AMBF)."""
        if a_name in ('World', 'world', '/ambf/env/World'):
            return self.get_world_handle()
        name, problem = self._find(a_name)
        if name is None:  # a body whose physics started after connect()
            self._read_catalog()
            name, problem = self._find(a_name)
        if name is None:
            print(f'{a_name} NAMED OBJECT NOT FOUND: {problem}')
            return None
        handle = self._objects.get(name)
        if handle is None:
            handle = RigidBody(name, afhub.Body(name.lstrip('/')))
            handle.set_active()
            self._objects[name] = handle
        return handle

    def get_obj_pose(self, a_name):
        handle = self.get_obj_handle(a_name)
        return None if handle is None else handle.get_pose()

    def set_obj_cmd(self, a_name, fx, fy, fz, nx, ny, nz):
        self.get_obj_handle(a_name).wrench_command(fx, fy, fz, nx, ny, nz)

    # ----- the publisher thread -----
    def _run_publishers(self):
        period = 1.0 / self._rate_hz
        deadline = time.monotonic()
        while self._running:
            for handle in list(self._objects.values()):
                if handle.is_active():
                    try:
                        handle.run_publisher()
                    except Exception as error:  # the hub gone, memory exhausted: say, go on
                        print(f'ambf_client: {handle.get_name()}: {error}', file=sys.stderr)
            deadline += period
            time.sleep(max(0.0, deadline - time.monotonic()))

    # ----- summaries -----
    def print_active_topics(self):
        print([name.lstrip('/') for name in self._names])  # afhub's channels

    def print_summary(self):
        print('_________________________________________________________')
        print('---------------------------------------------------------')
        print('CLIENT FOR CREATING OBJECTS FROM AFHUB CHANNELS')
        print('Common namespace: ', self._common_namespace)
        print('Number of OBJECTS found', len(self._names))
        for name in self._names:
            print(name)
        print('---------------------------------------------------------')

    def clean_up(self):
        """Stops re-sending commands (the physics' watchdog then releases the bodies)."""
        self._running = False
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join()
        self._thread = None
        for name in self._objects:
            print('Closing publisher for: ', name)
        self._objects.clear()

