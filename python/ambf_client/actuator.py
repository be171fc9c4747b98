"""A constraint actuator's handle, as AMBF's ``Actuator``: actuate() makes the actuator
hold the body that touches it, deactuate() lets go. Its flag travels in the command of
the body that carries it, which that body's handle sends and re-sends (so the physics'
watchdog does not release it)."""

from .handle import Handle


class Actuator(Handle):
    def __init__(self, name, carrier, index):
        """name: its AMBF name; carrier: the RigidBody handle of the body carrying it;
        index: its place among that body's actuators (command order)."""
        super().__init__(name)
        self._carrier = carrier
        self._index = index

    def run_publisher(self):
        """Nothing of its own to send: the carrier's handle sends the flag."""

    def actuate(self, obj_name, pose=None):
        """Holds the body touching the actuator. afhub's physics holds whatever body
        touches it: obj_name is not checked against it. An offset pose is not supported."""
        if pose is not None:
            raise NotImplementedError(
                'actuate(obj_name, pose): afhub holds the touching body where it touches; '
                'call actuate(obj_name) without a pose')
        self._carrier.set_actuator(self._index, True)

    def deactuate(self):
        """Lets go of what the actuator holds."""
        self._carrier.set_actuator(self._index, False)

    def get_parent_name(self):
        return self._carrier.get_name().rsplit('/', 1)[-1]
