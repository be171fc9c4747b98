"""A proximity sensor's handle, as AMBF's ``Sensor``: its rays' readings, from the state
of the body that carries it (afhub publishes a sensor's rays with that body's state, and
the catalog names the sensor of each ray)."""

from .handle import Handle


class Sensor(Handle):
    def __init__(self, name, body, rays):
        """name: its AMBF name; body: the afhub.Body carrying it; rays: the indices of its
        rays in that body's State.sensor_distances."""
        super().__init__(name)
        self._body = body
        self._rays = list(rays)

    def run_publisher(self):
        """Nothing to send: a sensor takes no command."""

    def _readings(self):
        state = self._body.read(wait_s=1.0)
        if state is None:
            raise RuntimeError(f'{self._name}: no state came from {self._body.channel} in 1 s: '
                               'is its simulation running?')
        return ([float(state.sensor_distances[r]) for r in self._rays],
                [float(state.sensor_ranges[r]) for r in self._rays])

    def _element(self, idx, values):
        """values[idx], or None for an index outside the sensor's elements (as AMBF)."""
        return values[idx] if isinstance(idx, int) and 0 <= idx < len(self._rays) else None

    def get_count(self):
        """The sensor's elements (rays)."""
        return len(self._rays)

    def is_triggered(self, idx):
        """Whether element idx sees a body within its range."""
        distances, _ = self._readings()
        distance = self._element(idx, distances)
        return None if distance is None else distance >= 0.0

    def get_range(self, idx=0):
        """Element idx's range, m."""
        return self._element(idx, self._readings()[1])

    def get_measurement(self, idx):
        """Element idx's normalized depth, as AMBF gives it: 1 - distance / range when it is
        triggered (1 at the sensor, 0 at its range's end), 0 when it is not."""
        distances, ranges = self._readings()
        distance, reach = self._element(idx, distances), self._element(idx, ranges)
        if distance is None:
            return None
        return 1.0 - distance / reach if distance >= 0.0 and reach > 0.0 else 0.0

    def get_distance(self, idx):
        """afhub's own: element idx's distance to what it sees, m, or -1 for nothing."""
        return self._element(idx, self._readings()[0])

    def get_sensed_object(self, idx):
        raise NotImplementedError(
            'get_sensed_object: afhub publishes how far each ray sees a body, not which body; '
            'is_triggered() and get_measurement() tell that and how deep')

    def get_parent_name(self):
        return self._body.channel.rsplit('/', 1)[-1]
