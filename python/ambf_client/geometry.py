"""The small message types AMBF's client hands out (geometry_msgs' Point, Quaternion,
Pose, Wrench, Twist: attributes x, y, z, w), and the fixed-axis roll-pitch-yaw
conversions AMBF uses ('sxyz': roll about x, then pitch about y, then yaw about z, all
about the world's axes)."""

import math
import numbers


def _number(value, name):
    """A coordinate as a float: a real number (numpy's too), not text or a bool, which
    float() would read ('1' as 1 N, True as 1)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f'{name} is a real number, not {value!r}')
    return float(value)


class Vector3:
    __slots__ = ('x', 'y', 'z')

    def __init__(self, x=0.0, y=0.0, z=0.0):
        self.x, self.y, self.z = _number(x, 'x'), _number(y, 'y'), _number(z, 'z')

    def __iter__(self):
        return iter((self.x, self.y, self.z))

    def __repr__(self):
        return f'x: {self.x}\ny: {self.y}\nz: {self.z}'


Point = Vector3


class Quaternion:
    """x, y, z, w: AMBF's (and ROS's) order."""
    __slots__ = ('x', 'y', 'z', 'w')

    def __init__(self, x=0.0, y=0.0, z=0.0, w=1.0):
        self.x, self.y, self.z = _number(x, 'x'), _number(y, 'y'), _number(z, 'z')
        self.w = _number(w, 'w')

    def __iter__(self):
        return iter((self.x, self.y, self.z, self.w))

    def __repr__(self):
        return f'x: {self.x}\ny: {self.y}\nz: {self.z}\nw: {self.w}'


class Pose:
    __slots__ = ('position', 'orientation')

    def __init__(self, position=None, orientation=None):
        self.position = position if position is not None else Point()
        self.orientation = orientation if orientation is not None else Quaternion()


class Wrench:
    __slots__ = ('force', 'torque')

    def __init__(self, force=None, torque=None):
        self.force = force if force is not None else Vector3()
        self.torque = torque if torque is not None else Vector3()


class Twist:
    __slots__ = ('linear', 'angular')

    def __init__(self, linear=None, angular=None):
        self.linear = linear if linear is not None else Vector3()
        self.angular = angular if angular is not None else Vector3()


def quaternion_from_rpy(roll, pitch, yaw):
    """x, y, z, w of the rotation Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


def rpy_from_quaternion(x, y, z, w):
    """roll, pitch, yaw (fixed axes x, y, z) of a unit quaternion."""
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw
