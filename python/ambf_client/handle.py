"""What every object handle of AMBF's client has: its name, and whether the client's
thread publishes for it (get_obj_handle makes it active)."""


class Handle:
    def __init__(self, name):
        self._name = name
        self._active = False
        self._closed = False  # its client was cleaned up: nothing sends its commands again

    def close(self):
        self._active = False
        self._closed = True

    def require_open(self):
        """Setters of a closed handle would send once and never again (the physics'
        watchdog then releases the body): refused instead."""
        if self._closed:
            raise RuntimeError(f"{self._name}: this handle's client was cleaned up "
                               f"(clean_up()), so its commands would not be sent again: "
                               f"connect() and get a new handle")

    def get_name(self):
        return self._name

    def is_active(self):
        return self._active

    def set_active(self):
        self._active = True
