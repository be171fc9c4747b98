"""Cameras and lights, as AMBF's ``Camera`` and ``Light``: afhub does not render, so
every call of theirs but get_name() raises NotImplementedError naming the call."""

from .handle import Handle


class _Unrendered(Handle):
    _kind = ''

    def is_active(self):
        return False  # nothing for the client's thread to send

    def set_active(self):
        pass

    def __getattr__(self, call):
        if call.startswith('__'):
            raise AttributeError(call)

        def unsupported(*args, **kwargs):
            raise NotImplementedError(
                f"{call}: {self._name} is a {self._kind}; afhub simulates physics and does "
                "not render, so its cameras and lights offer no calls (`afhub view` shows "
                "the scene)")
        unsupported.__name__ = call
        return unsupported


class Camera(_Unrendered):
    _kind = 'camera'


class Light(_Unrendered):
    _kind = 'light'
