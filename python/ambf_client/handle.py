"""What every object handle of AMBF's client has: its name, and whether the client's
thread publishes for it (get_obj_handle makes it active)."""


class Handle:
    def __init__(self, name):
        self._name = name
        self._active = False

    def get_name(self):
        return self._name

    def is_active(self):
        return self._active

    def set_active(self):
        self._active = True
