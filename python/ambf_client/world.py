"""The world's handle, as AMBF's ``World``: simulated time and step, reset, and
client-driven stepping (AMBF's step throttling), which afhub gives by pausing the world
and stepping it from update()."""

import afhub

from .handle import Handle


class World(Handle):
    def __init__(self, name='World'):
        super().__init__(name)
        self._world = afhub.World()
        self._throttling = False
        self._step_skips = 1

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
        data = bool(data)
        if data and not self._throttling:
            self._world.pause()
        elif not data and self._throttling:
            self._world.resume()
        self._throttling = data

    def set_num_step_skips(self, n):
        if n <= 0 or n > 100:
            raise ValueError('set_num_step_skips takes 1 to 100 steps')
        self._step_skips = int(n)

    def update(self):
        """With throttling: advances the world by the step skips and waits until it has."""
        if self._throttling:
            self._world.step(self._step_skips)

    def run_publisher(self):
        """Nothing to re-send: world commands act once each."""

    def clear_cmd(self):
        self.enable_throttling(False)
