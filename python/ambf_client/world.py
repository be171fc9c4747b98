"""The world's handle, as AMBF's ``World``: simulated time and step, reset, and
client-driven stepping (AMBF's step throttling), which afhub gives by pausing the world
and stepping it from update()."""

import operator
import time

import afhub

from .handle import Handle

# The throttling client's pause is held: it lasts while the client's publisher thread
# renews it, and lapses a second after the script dies or stalls (AMBF's world runs on
# once its throttling client goes quiet). Renewed five times a second.
THROTTLING_HOLD_S = 1.0
RENEW_EVERY_S = 0.2


class World(Handle):
    def __init__(self, name='World', namespace=''):
        super().__init__(name)
        self.namespace = namespace  # `afhub run --namespace`
        self._world = afhub.World(namespace)
        self._throttling = False
        self._step_skips = 1
        self._renewed = 0.0  # time.monotonic() of the last renewal

    def set_name(self, name):
        self._name = name

    def get_sim_time(self):
        return self._world.sim_time()

    def get_wall_time(self):
        return self._world.state()['wall_time']

    def get_sim_step(self):
        return self._world.sim_step()

    def reset(self):
        """Every body back where the model starts it, commands cleared, step 0."""
        self._world.reset()

    def reset_bodies(self):
        """afhub resets the bodies and the clock together: as reset()."""
        self._world.reset()

    def enable_throttling(self, data):
        """True: the world advances only when the client calls update(), by
        set_num_step_skips() steps each time (the world is paused in between); False: it
        runs on in real time."""
        self.require_open()
        data = bool(data)
        if data and not self._throttling:
            self._world.pause(hold_s=THROTTLING_HOLD_S)
            self._renewed = time.monotonic()
        elif not data and self._throttling:
            self._world.release()
        self._throttling = data

    def release_throttling(self):
        """The world runs on, as AMBF's world does once its throttling client goes quiet:
        the client calls it when cleaned up and when the script ends. Only this client's
        hold ends: a pause of the user's (afhub world pause) or another throttling
        client's stays. A hub that is gone has nothing to release: said, not raised."""
        if not self._throttling:
            return
        self._throttling = False
        try:
            self._world.release()
        except afhub.Error as error:
            print(f'ambf_client: the world paused for throttling was not released: {error}')

    def set_num_step_skips(self, n):
        try:
            steps = None if isinstance(n, bool) else operator.index(n)
        except TypeError:
            steps = None
        if steps is None or not 1 <= steps <= 100:
            raise ValueError(f'set_num_step_skips takes a whole number of steps, 1 to 100, '
                             f'not {n!r}')
        self._step_skips = steps

    def update(self):
        """With throttling: advances the world by the step skips and waits until it has.
        A hold that lapsed while the script stalled is taken again first."""
        self.require_open()
        if self._throttling:
            # paused_by_pid, not paused: a world running another client's single steps is
            # paused still, and a pause now would end those steps.
            if not self._world.state()['paused_by_pid']:
                self._world.pause(hold_s=THROTTLING_HOLD_S)
            self._world.step(self._step_skips)

    def run_publisher(self):
        """Called by the client's publisher thread: renews the throttling pause."""
        if self._throttling and time.monotonic() - self._renewed >= RENEW_EVERY_S:
            self._world.hold()
            self._renewed = time.monotonic()

    def clear_cmd(self):
        self.enable_throttling(False)
