"""A rigid body's handle, as AMBF's ``RigidBody``: getters read the body's newest state
from shared memory; setters change the command this handle holds, which is sent at once
and then again at the client's publish rate by its background thread (so the physics'
watchdog never releases it while the script sleeps or waits on input()). As in AMBF, a
wrench not set again within ``time_out`` seconds is cleared: forces and torques must be
refreshed; joint and pose commands hold."""

import collections
import copy
import operator
import sys
import threading
import time

import afhub

from .geometry import (_number, Point, Pose, Quaternion, Twist, Vector3, Wrench,
                       quaternion_from_rpy, rpy_from_quaternion)
from .handle import Handle

_EFFORT, _POSITION, _VELOCITY = afhub.JointType.EFFORT, afhub.JointType.POSITION, \
    afhub.JointType.VELOCITY


def _whole(idx):
    """A joint index as an int (a numpy integer too), or None: a bool, a float, a name."""
    if isinstance(idx, bool):
        return None
    try:
        return operator.index(idx)
    except TypeError:
        return None


def _unsupported(call, why):
    def method(self, *args, **kwargs):
        raise NotImplementedError(f'{call}: {why}')
    method.__name__ = call
    method.__doc__ = f'Not available on afhub: {why}.'
    return method


def _quaternion_szyx(roll, pitch, yaw):
    """AMBF's pose_command rotation: static axes z, y, x by roll, pitch, yaw."""
    # Rx(yaw) * Ry(pitch) * Rz(roll), as quaternions (x, y, z, w).
    def multiply(a, b):
        ax, ay, az, aw = a
        bx, by, bz, bw = b
        return (aw * bx + ax * bw + ay * bz - az * by,
                aw * by - ax * bz + ay * bw + az * bx,
                aw * bz + ax * by - ay * bx + az * bw,
                aw * bw - ax * bx - ay * by - az * bz)
    return multiply(multiply(quaternion_from_rpy(yaw, 0, 0), quaternion_from_rpy(0, pitch, 0)),
                    quaternion_from_rpy(0, 0, roll))


class RigidBody(Handle):
    def __init__(self, name, body, time_out=0.1):
        super().__init__(name)
        self._body = body
        self._time_out = time_out
        self._lock = threading.Lock()
        self._joint_names = list(body.joint_names)
        self._joint_cmds = []
        self._joint_types = []
        self._cartesian = 'force'
        self._wrench = Wrench()
        self._pose = None
        self._twist = Twist()
        self._pose_cmd_set = self._twist_cmd_set = self._wrench_cmd_set = False
        self._actuators = []  # flags of the body's actuators, once one is set
        self._last_command = 0.0
        self._told_refusal = None
        # The command held before each of the last setters: a command the physics refuses
        # (a value beyond the body's bounds, which only the physics knows) is dropped by
        # going back to the one before it, which the physics took; re-sent, the refused
        # one let the watchdog release the body.
        self._before = collections.deque(maxlen=16)
        self._publish_flags = {'children': True, 'joint_names': True, 'joint_positions': True}

    # ----- state -----
    def _state(self):
        with self._lock:  # the publisher thread uses the same afhub.Body
            state = self._body.read(wait_s=1.0)
        if state is None:
            raise RuntimeError(f'{self._name}: no state came from {self._body.channel} in 1 s: '
                               'is its simulation running?')
        return state

    def get_sim_step(self):
        return self._state().step

    def get_pos(self):
        return Point(*self._state().position)

    def get_rot(self):
        """The orientation as a quaternion x, y, z, w (AMBF's order)."""
        return Quaternion(*self._state().orientation)

    def get_rpy(self):
        """Fixed-axis roll, pitch, yaw (AMBF's 'sxyz')."""
        return rpy_from_quaternion(*self._state().orientation)

    def get_pose(self):
        """[x, y, z, roll, pitch, yaw], as AMBF returns it."""
        state = self._state()
        return list(state.position) + list(rpy_from_quaternion(*state.orientation))

    def get_linear_vel(self):
        return Vector3(*self._state().linear_velocity)

    def get_angular_vel(self):
        return Vector3(*self._state().angular_velocity)

    def get_inertia(self):
        return Point(*self._state().inertia)

    def get_mass(self):
        return self._state().mass

    def get_num_joints(self):
        return len(self._joint_names)

    def get_joint_names(self):
        return list(self._joint_names)

    def get_joint_idx_from_name(self, joint_name):
        if joint_name in self._joint_names:
            return self._joint_names.index(joint_name)
        print(f'ERROR! Requested Joint "{joint_name}" not found in list of joints:')
        print(self._joint_names)
        return None

    def get_joint_name_from_idx(self, joint_idx):
        if self.is_joint_idx_valid(joint_idx):
            return self._joint_names[joint_idx]
        return None

    def is_joint_idx_valid(self, joint_idx):
        n = len(self._joint_names)
        if _whole(joint_idx) is not None and 0 <= joint_idx < n:
            return True
        print(f'ERROR! Requested Joint Idx of "{joint_idx}" outside valid range [0 - {n - 1}]')
        return False

    def _index(self, joint_name_or_idx):
        if isinstance(joint_name_or_idx, str):
            idx = self.get_joint_idx_from_name(joint_name_or_idx)
            return idx
        return _whole(joint_name_or_idx) if self.is_joint_idx_valid(joint_name_or_idx) else None

    def _joint_value(self, joint_name_or_idx, field):
        idx = self._index(joint_name_or_idx)
        return None if idx is None else float(getattr(self._state(), field)[idx])

    def get_joint_pos(self, joint_name_or_idx):
        return self._joint_value(joint_name_or_idx, 'joint_positions')

    def get_joint_vel(self, joint_name_or_idx):
        return self._joint_value(joint_name_or_idx, 'joint_velocities')

    def get_joint_effort(self, joint_name_or_idx):
        return self._joint_value(joint_name_or_idx, 'joint_efforts')

    def get_all_joint_pos(self):
        return self._state().joint_positions.tolist()

    def get_all_joint_vel(self):
        return self._state().joint_velocities.tolist()

    def get_all_joint_effort(self):
        return self._state().joint_efforts.tolist()

    # ----- what was commanded -----
    def get_pos_command(self):
        return Point(*self._pose.position) if self._pose_cmd_set else self.get_pos()

    def get_rot_command(self):
        return Quaternion(*self._pose.orientation) if self._pose_cmd_set else self.get_rot()

    def get_force_command(self):
        return Vector3(*self._wrench.force)

    def get_torque_command(self):
        return Vector3(*self._wrench.torque)

    def get_linear_velocity_command(self):
        return Vector3(*self._twist.linear) if self._twist_cmd_set else self.get_linear_vel()

    def get_angular_velocity_command(self):
        return Vector3(*self._twist.angular) if self._twist_cmd_set else self.get_angular_vel()

    # afhub publishes every body's joint names and positions, always: these flags are kept
    # for scripts that set them, and change nothing.
    def get_publish_children_name_flag(self):
        return self._publish_flags['children']

    def get_publish_joint_names_flag(self):
        return self._publish_flags['joint_names']

    def get_publish_joint_positions_flag(self):
        return self._publish_flags['joint_positions']

    def set_publish_children_names_flag(self, state):
        self._publish_flags['children'] = bool(state)

    def set_publish_joint_names_flag(self, state):
        self._publish_flags['joint_names'] = bool(state)

    def set_publish_joint_positions_flag(self, state):
        self._publish_flags['joint_positions'] = bool(state)

    def get_children_names(self):
        """The bodies jointed directly below this one (their model names)."""
        return list(self._body.child_names)

    def get_num_of_children(self):
        return len(self._body.child_names)

    def get_parent_name(self):
        """The body this one is jointed below (its model name), or '' for a root."""
        return self._body.parent_name

    get_identifier = _unsupported('get_identifier', 'afhub states carry no identifier')
    get_msg_header = _unsupported('get_msg_header', 'afhub states are not ROS messages')
    get_msg_time_stamp = _unsupported('get_msg_time_stamp',
                                      'afhub states are not ROS messages (afhub.State.stamp_ns)')
    get_msg_seq_num = _unsupported('get_msg_seq_num', 'afhub states are not ROS messages')
    get_msg_frame_id = _unsupported('get_msg_frame_id', 'afhub states are not ROS messages')

    # ----- commands -----
    def _joints_for(self):
        n = len(self._joint_names)
        if len(self._joint_cmds) != n:
            self._joint_cmds = [0.0] * n
            self._joint_types = [_EFFORT] * n

    def _set_joints(self, pairs, kind):
        # Every value made a number before any is kept: a refused call changes nothing.
        pairs = [(idx, _number(value, 'a joint value')) for idx, value in pairs]
        with self._lock:
            held = self._held()
            self._joints_for()
            for idx, value in pairs:
                self._joint_cmds[idx] = value
                self._joint_types[idx] = kind
        self._apply_command(held)

    def _set_joint(self, joint_name_or_idx, value, kind):
        idx = self._index(joint_name_or_idx)
        if idx is not None:
            self._set_joints([(idx, value)], kind)

    def set_joint_pos(self, joint_name_or_idx, q):
        self._set_joint(joint_name_or_idx, q, _POSITION)

    def set_joint_vel(self, joint_name_or_idx, qd):
        self._set_joint(joint_name_or_idx, qd, _VELOCITY)

    def set_joint_effort(self, joint_name_or_idx, effort):
        self._set_joint(joint_name_or_idx, effort, _EFFORT)

    def _set_multiple(self, values, index_list, kind):
        """As AMBF: `values` is a vector over the joints, and each joint of `index_list`
        takes its own entry, values[idx]; the joints not listed keep their commands. With
        no index list (afhub's default; AMBF needs one), every joint `values` reaches."""
        n = len(self._joint_names)
        values = list(values)
        if index_list is None:
            if len(values) > n:  # as AMBF, which said so for each value past the last joint
                print(f'Requested Joint index is out of range with joints {n}: '
                      f'{len(values)} values given, the last {len(values) - n} left out')
            index_list = range(min(n, len(values)))
        indices = [_whole(idx) for idx in index_list]
        if any(idx is None or not 0 <= idx < n for idx in indices):
            print(f'Requested Joint index is out of range with joints {n}: {list(index_list)}')
            return
        if indices and max(indices) >= len(values):
            raise IndexError(
                f'joint {max(indices)} has no value: {len(values)} values given. As in AMBF, '
                f'joint i takes values[i]: give a value for each joint up to the last listed')
        self._set_joints([(idx, values[idx]) for idx in indices], kind)

    def set_multiple_joint_pos(self, q_list, index_list=None):
        self._set_multiple(q_list, index_list, _POSITION)

    def set_multiple_joint_vel(self, qd_list, index_list=None):
        self._set_multiple(qd_list, index_list, _VELOCITY)

    def set_multiple_joint_effort(self, efforts, index_list=None):
        self._set_multiple(efforts, index_list, _EFFORT)

    def set_wrench(self, wrench):
        with self._lock:
            held = self._held()
            self._cartesian = 'force'
            self._wrench = Wrench(Vector3(*_xyz(wrench.force)), Vector3(*_xyz(wrench.torque)))
            self._wrench_cmd_set = True
        self._apply_command(held)

    def set_force(self, fx, fy, fz):
        self.set_wrench(Wrench(Vector3(fx, fy, fz), self.get_torque_command()))

    def set_torque(self, nx, ny, nz):
        self.set_wrench(Wrench(self.get_force_command(), Vector3(nx, ny, nz)))

    def wrench_command(self, fx, fy, fz, nx, ny, nz):
        self.set_wrench(Wrench(Vector3(fx, fy, fz), Vector3(nx, ny, nz)))

    def set_pose(self, pose):
        with self._lock:
            held = self._held()
            self._cartesian = 'position'
            self._pose = Pose(Point(*_xyz(pose.position)),
                              Quaternion(*_xyzw(pose.orientation)))
            self._pose_cmd_set = True
        self._apply_command(held)

    def set_pos(self, px, py, pz):
        self.set_pose(Pose(Point(px, py, pz), self.get_rot_command()))

    def set_rot(self, quat):
        """quat: x, y, z, w (a list, or an object with those attributes)."""
        self.set_pose(Pose(self.get_pos_command(), Quaternion(*_xyzw(quat))))

    def set_rpy(self, roll, pitch, yaw):
        self.set_rot(quaternion_from_rpy(roll, pitch, yaw))

    def pose_command(self, px, py, pz, roll, pitch, yaw, *jnt_cmds):
        """A pose target (rotation as AMBF's pose_command computes it: static axes z, y, x);
        jnt_cmds, when given, are position targets for joints 0, 1, ..."""
        self.set_pose(Pose(Point(px, py, pz), Quaternion(*_quaternion_szyx(roll, pitch, yaw))))
        if jnt_cmds:
            self.set_multiple_joint_pos(list(jnt_cmds), list(range(len(jnt_cmds))))

    def set_twist(self, twist):
        with self._lock:
            held = self._held()
            self._cartesian = 'velocity'
            self._twist = Twist(Vector3(*_xyz(twist.linear)), Vector3(*_xyz(twist.angular)))
            self._twist_cmd_set = True
        self._apply_command(held)

    def set_linear_vel(self, vx, vy, vz):
        self.set_twist(Twist(Vector3(vx, vy, vz), self.get_angular_velocity_command()))

    def set_angular_vel(self, ax, ay, az):
        self.set_twist(Twist(self.get_linear_velocity_command(), Vector3(ax, ay, az)))

    def velocity_command(self, vx, vy, vz, ax, ay, az):
        self.set_twist(Twist(Vector3(vx, vy, vz), Vector3(ax, ay, az)))

    def set_actuator(self, index, engage):
        """Engages or releases the body's actuator `index` (an Actuator handle calls it)."""
        with self._lock:
            held = self._held()
            if not self._actuators:
                self._actuators = [False] * len(self._body.actuator_names)
            self._actuators[index] = bool(engage)
        self._apply_command(held)

    # What the handle's command is made of (the setters change it; run_publisher sends it).
    _COMMAND = ('_joint_cmds', '_joint_types', '_cartesian', '_wrench', '_pose', '_twist',
                '_pose_cmd_set', '_twist_cmd_set', '_wrench_cmd_set', '_actuators')

    def _held(self):
        """The command as it is, to put back (under the lock)."""
        return {name: copy.copy(getattr(self, name)) for name in self._COMMAND}

    def _apply_command(self, held):
        """Sends the command a setter just changed. Values refused before anything is sent
        (not finite, too many joints: ValueError, or any other error) put back the command `held` before the
        change, so that the next setter and the client's thread send that one, not the
        refused values again."""
        self.require_open()
        # Every command feeds the wrench's watchdog, as in AMBF.
        now = time.monotonic()
        with self._lock:
            self._active = True
            self._last_command = now
        try:
            sent = self.run_publisher(now)
        except Exception:
            with self._lock:
                self._restore(held)
            raise
        if sent:
            with self._lock:
                self._before.append(held)

    def _restore(self, held):
        for name, value in held.items():
            setattr(self, name, value)

    def run_publisher(self, now=None):
        """Sends the command this handle holds (the client's thread calls it at its rate);
        False when the physics had refused an earlier one, which is then dropped (the
        command goes back to the one held before the setter that made it) and this one is
        not sent. A wrench not refreshed within time_out is cleared first, as AMBF does."""
        now = time.monotonic() if now is None else now
        with self._lock:
            if self._cartesian == 'force' and now - self._last_command > self._time_out:
                self._wrench = Wrench()
            kwargs = {}
            if self._cartesian == 'force':
                kwargs = {'force': tuple(self._wrench.force), 'torque': tuple(self._wrench.torque)}
            elif self._cartesian == 'position':
                kwargs = {'position': tuple(self._pose.position),
                          'orientation': tuple(self._pose.orientation)}
            else:
                kwargs = {'linear_velocity': tuple(self._twist.linear),
                          'angular_velocity': tuple(self._twist.angular)}
            joints = (self._joint_cmds, self._joint_types) if self._joint_cmds else (None, None)
            if self._actuators:
                kwargs['actuators'] = self._actuators
            try:
                self._body.command(joints[0], joints[1], **kwargs)
                return True
            except afhub.CommandRefused as refusal:
                if self._before:
                    self._restore(self._before.pop())
                if str(refusal) != self._told_refusal:
                    print(f'ambf_client: {refusal}; {self._name} goes back to the command it '
                          'held before the setter that made it', file=sys.stderr)
                    self._told_refusal = str(refusal)
                return False


def _xyz(v):
    return (v.x, v.y, v.z) if hasattr(v, 'x') else tuple(v)


def _xyzw(q):
    xyzw = (q.x, q.y, q.z, q.w) if hasattr(q, 'w') else tuple(q)
    if len(xyzw) != 4:  # three values became (x, y, z, 1), a rotation nobody asked for
        raise ValueError(f'a quaternion takes four values x, y, z, w, not {len(xyzw)}')
    return xyzw
