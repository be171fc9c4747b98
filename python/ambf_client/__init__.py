"""AMBF's Python client on afhub: scripts written for AMBF's ``ambf_client`` run unchanged.

    from ambf_client import Client
    client = Client('my_script')
    client.connect()
    arm = client.get_obj_handle('arm/base')
    arm.set_joint_pos(0, 0.5)

It stands on the native module ``afhub`` (shared memory, no ROS): see docs/python.md for
what is supported and where afhub departs from AMBF.
"""

from .actuator import Actuator
from .client import Client
from .geometry import Point, Pose, Quaternion, Twist, Vector3, Wrench
from .rigid_body import RigidBody
from .sensor import Sensor
from .unrendered import Camera, Light
from .world import World

__all__ = ['Client', 'RigidBody', 'World', 'Sensor', 'Actuator', 'Camera', 'Light', 'Point',
           'Quaternion', 'Pose', 'Vector3', 'Wrench', 'Twist']
