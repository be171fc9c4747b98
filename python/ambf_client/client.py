"""AMBF's ``Client`` on afhub: finds the simulated bodies, their sensors and actuators in
afhub's catalog, and the world's cameras and lights in its world state, instead of ROS
topics; hands out handles to them, and re-sends every handle's command at the publish
rate from a background thread."""

import atexit
import os
import sys
import threading
import time

import afhub

from .actuator import Actuator
from .rigid_body import RigidBody
from .sensor import Sensor
from .unrendered import Camera, Light
from .world import World


def _publish_rate(rate_hz):
    """The rate commands are sent again at: refreshed slower than 10 Hz, a body would be
    released by the physics' watchdog (0.5 s by default) between two sends."""
    rate_hz = float(rate_hz)
    if not 10.0 <= rate_hz <= 100000.0:
        raise ValueError(f'default_publish_rate takes 10 to 100000 Hz, got {rate_hz}: commands '
                         'sent less often than the watchdog period (0.5 s) let a body go')
    return rate_hz


class Client:
    def __init__(self, client_name='ambf_client'):
        self._client_name = client_name
        self._objects = {}  # AMBF name ('/ambf/env/ecm/baselink') -> handle, once asked for
        self._names = []  # AMBF names of the live bodies, from the catalog
        # AMBF name of a sensor, actuator, camera or light -> (kind, carrier body, rays or
        # index)
        self._parts = {}
        self._world_reader = None  # afhub.World: the world state names cameras and lights
        # The namespace of the bodies' world (`afhub run --namespace`), None for none, and
        # the body and publisher it was found from.
        self._world_namespace = None
        self._world_found_from = None
        self._common_namespace = ''
        self._world = None
        self._rate_hz = 120.0
        self._thread = None
        self._running = False
        self._exit_hooked = False

    # ----- connecting -----
    def connect(self, default_publish_rate=120):
        """Joins the hub, reads the catalog and starts the thread re-sending commands."""
        self._rate_hz = _publish_rate(default_publish_rate)
        afhub.connect(wait_s=float(os.environ.get('AFHUB_WAIT', '0')))
        self._read_catalog()
        self.start()
        if not self._exit_hooked:  # a script that ends throttling leaves the world running
            atexit.register(self._release_world)
            self._exit_hooked = True

    def create_objs_from_rostopics(self, publish_rate):
        self._rate_hz = _publish_rate(publish_rate)
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
        self._rate_hz = _publish_rate(rate)

    def _read_catalog(self):
        self._names, self._parts = [], {}
        entries = [entry for entry in afhub.catalog() if entry['kind'] == 'body']
        for entry in entries:
            body = '/' + entry['channel']
            self._names.append(body)
            namespace = body[:body.rfind('/') + 1]  # a body's parts are named in its namespace
            for ray, sensor in enumerate(entry['sensor_rays']):
                self._parts.setdefault(namespace + sensor, ('sensor', body, []))[2].append(ray)
            for index, actuator in enumerate(entry['actuator_names']):
                self._parts[namespace + actuator] = ('actuator', body, index)
        self._find_world(entries)
        if self._world_reader is not None:
            try:
                state = self._world_reader.state(wait_s=1.0)
                for kind in ('camera', 'light'):
                    for name in state[kind + 's']:
                        self._parts['/' + name.lstrip('/')] = (kind, None, None)
            except afhub.Error:  # its physics ended meanwhile
                pass
        self._common_namespace = os.path.commonprefix(self._names) if self._names else ''
        if self._common_namespace and not self._common_namespace.endswith('/'):
            self._common_namespace = self._common_namespace[:self._common_namespace.rfind('/') + 1]

    def _find_world(self, entries):
        """The world of the bodies' physics (AMBF has one world): with several `afhub run`,
        the default namespace's, else that of the first body an `afhub run` publishes
        (before `afhub synth`'s and others'), in its namespace (`afhub run --namespace NS`:
        World() of the default one found nothing). Looked for again when the bodies'
        publishers changed, or none was found. None when no world publishes them: then
        there is no world handle, as in AMBF with no world."""
        physics = [e for e in entries if e['owner'].startswith('afhub-physics')]
        first_of_each = {}  # a body of each `afhub run` (or the first body), in that order
        for entry in physics or entries[:1]:
            first_of_each.setdefault(entry['owner_pid'], entry['channel'])
        found_from = tuple(first_of_each.items())
        if found_from == self._world_found_from and self._world_namespace is not None:
            return
        self._world_found_from = found_from
        worlds = []
        for channel in first_of_each.values():
            try:
                name_space = afhub.world_namespace(channel)
            except afhub.Error:  # the body went meanwhile
                continue
            if name_space is not None and name_space not in worlds:
                worlds.append(name_space)
        name_space = '' if '' in worlds else (worlds[0] if worlds else None)
        if len(worlds) > 1 and name_space != self._world_namespace:
            print(f"ambf_client: {len(worlds)} simulations run (namespaces "
                  f"{', '.join(repr(w) for w in worlds)}); the world handle is that of namespace "
                  f"{name_space!r}", file=sys.stderr)
        if name_space != self._world_namespace or self._world_reader is None:
            self._world_reader = afhub.World(name_space) if name_space is not None else None
        self._world_namespace = name_space

    # ----- names and handles -----
    def get_common_namespace(self):
        return self._common_namespace

    def get_obj_names(self):
        """Every live body's AMBF name ('/ambf/env/ecm/baselink'), then its sensors',
        actuators', cameras' and lights', and 'World' when a simulation runs."""
        self._read_catalog()
        world = ['World'] if self._world_namespace is not None else []
        return world + list(self._names) + list(self._parts)

    def get_world_handle(self):
        if self._thread is None:  # a throttling pause is held by its thread
            raise RuntimeError('get_world_handle: the client is not connected: call connect() '
                               'first (its thread keeps the throttling pause held)')
        if self._world_namespace is None:  # a physics started after connect()
            self._read_catalog()
        if self._world_namespace is None:  # as AMBF with no world: none
            print('World NAMED OBJECT NOT FOUND: no simulation runs (`afhub run MODEL`)')
            return None
        if self._world is None or self._world.namespace != self._world_namespace:
            if self._world is not None:
                self._release_world()
            self._world = World('World', self._world_namespace)
            self._world.set_active()
        return self._world

    def _find(self, a_name):
        names = self._names + list(self._parts)
        for candidate in (a_name, '/' + a_name.lstrip('/')):
            if candidate in names:
                return candidate, None
        suffix = '/' + a_name.lstrip('/')
        parts = [name for name in self._parts if name.endswith(suffix)]
        try:  # afhub's rule: a unique suffix after a '/'
            body = '/' + afhub.resolve(a_name.lstrip('/'))
            if not parts:
                return body, None
            message = f'{a_name} names {body} and {", ".join(parts)}'
        except afhub.Error as error:
            if len(parts) == 1:
                return parts[0], None
            message = str(error) + (f'; or one of {", ".join(parts)}' if parts else '')
        matches = [name for name in names if a_name in name]  # AMBF's rule: a substring
        if len(matches) == 1:
            return matches[0], None
        if matches:  # as AMBF's "FOUND N WITH MATCHING NAME", naming them
            return None, f'{len(matches)} objects match it: {", ".join(matches)}'
        return None, message

    def get_obj_handle(self, a_name):
        """A handle to the body named a_name: its full AMBF name ('/ambf/env/ecm/baselink'),
        a part of it after a '/' ('ecm/baselink', 'baselink'), any part that only one body's
        name holds, or 'World' ('world' too, unless a body has that name). None when none
        or several match, saying which (as AMBF)."""
        if not isinstance(a_name, str):
            raise TypeError(f'get_obj_handle takes a name (str), not {type(a_name).__name__}')
        if self._thread is None:  # its setters would send once, then nothing would
            raise RuntimeError('get_obj_handle: the client is not connected: call connect() '
                               "first (its thread sends the handles' commands at its rate)")
        if a_name in ('World', '/ambf/env/World'):
            return self.get_world_handle()
        name, problem = self._find(a_name)
        if name is None:  # a body whose physics started after connect()
            self._read_catalog()
            name, problem = self._find(a_name)
        if name is None and a_name == 'world' and not any(  # a body named so comes first
                n.rsplit('/', 1)[-1] == 'world' for n in self._names):
            return self.get_world_handle()
        if name is None:
            print(f'{a_name} NAMED OBJECT NOT FOUND: {problem}')
            return None
        handle = self._objects.get(name)
        if handle is None:
            handle = self._open(name)
            handle.set_active()
            self._objects[name] = handle
        return handle

    def _open(self, name):
        kind, body, where = self._parts.get(name, ('body', name, None))
        if kind == 'body':
            return RigidBody(name, afhub.Body(body.lstrip('/')))
        if kind == 'sensor':  # a reader of its own: the publisher thread uses the carrier's
            return Sensor(name, afhub.Body(body.lstrip('/')), where)
        if kind == 'actuator':  # its flag travels in the carrier's command
            return Actuator(name, self.get_obj_handle(body), where)
        return Camera(name) if kind == 'camera' else Light(name)

    def get_obj_pose(self, a_name):
        handle = self.get_obj_handle(a_name)
        return None if handle is None else handle.get_pose()

    def set_obj_cmd(self, a_name, fx, fy, fz, nx, ny, nz):
        self.get_obj_handle(a_name).wrench_command(fx, fy, fz, nx, ny, nz)

    # ----- the publisher thread -----
    def _run_publishers(self):
        period = 1.0 / self._rate_hz
        deadline = time.monotonic()
        told = {}  # each handle's last fault, said once rather than at the thread's rate
        while self._running:
            world = [self._world] if self._world is not None else []
            for handle in list(self._objects.values()) + world:
                if handle.is_active():
                    try:
                        handle.run_publisher()
                        told.pop(handle.get_name(), None)
                    except Exception as error:  # the hub gone, memory exhausted: say, go on
                        if told.get(handle.get_name()) != str(error):
                            told[handle.get_name()] = str(error)
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
        for name, handle in self._objects.items():
            print('Closing publisher for: ', name)
            handle.close()
        self._objects.clear()
        self._release_world()

    def _release_world(self):
        if self._world is not None:
            self._world.release_throttling()
            self._world.close()
            self._world = None

