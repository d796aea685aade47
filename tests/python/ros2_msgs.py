"""ROS 2 (Jazzy) standard messages as Cyclone DDS Python IDL types, for the integration tests.

The tests check Caravan's ROS 2 bridge (RustDDS) against an independent DDS implementation:
``ros2_probe.py`` publishes and listens with these types through Cyclone DDS. Each class carries
the DDS type name ROS 2 puts on the wire (``sensor_msgs::msg::dds_::LaserScan_``) and the fields
of the ROS .msg definition in the same order with the same IDL types: fixed-size ROS arrays
(``float64[9]``) are IDL arrays, ``T[]`` unbounded sequences, every struct final (plain CDR, as
rmw_cyclonedds and RustDDS write it). Every field defaults to zero / empty.

Use with the .venv-ros2 environment (``python/caravan-python --venv ros2 --requirements
../tests/requirements-ros2.txt --setup``)::

    from ros2_msgs import TYPES, to_dict, from_dict
    scan = from_dict(TYPES["sensor_msgs/msg/LaserScan"], {"ranges": [1.0, 2.0]})
    to_dict(scan)  # -> {"header": {...}, "angle_min": 0.0, ..., "ranges": [1.0, 2.0], ...}
"""

import typing
from dataclasses import dataclass, field, fields, is_dataclass

import cyclonedds.idl.types as types
from cyclonedds.idl import IdlStruct

float32 = types.float32
float64 = types.float64
int8 = types.int8
int32 = types.int32
uint32 = types.uint32


def _zeros(n):
    return field(default_factory=lambda: [0.0] * n)


def _empty():
    return field(default_factory=list)


def _of(cls):
    return field(default_factory=cls)


# builtin_interfaces


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32 = 0
    nanosec: uint32 = 0


# std_msgs


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time = _of(Time)
    frame_id: str = ""


# geometry_msgs


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    # The .msg defaults w to 1, but on the wire a default is just a value: zero here, like
    # every other field, so that a missing field means zero everywhere.
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 0.0


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point = _of(Point)
    orientation: Quaternion = _of(Quaternion)


@dataclass
class Pose2D(IdlStruct, typename="geometry_msgs::msg::dds_::Pose2D_"):
    x: float64 = 0.0
    y: float64 = 0.0
    theta: float64 = 0.0


@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header = _of(Header)
    pose: Pose = _of(Pose)


@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Pose = _of(Pose)
    covariance: types.array[float64, 36] = _zeros(36)


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3 = _of(Vector3)
    angular: Vector3 = _of(Vector3)


@dataclass
class TwistWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    twist: Twist = _of(Twist)
    covariance: types.array[float64, 36] = _zeros(36)


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3 = _of(Vector3)
    rotation: Quaternion = _of(Quaternion)


@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header = _of(Header)
    child_frame_id: str = ""
    transform: Transform = _of(Transform)


@dataclass
class Wrench(IdlStruct, typename="geometry_msgs::msg::dds_::Wrench_"):
    force: Vector3 = _of(Vector3)
    torque: Vector3 = _of(Vector3)


@dataclass
class WrenchStamped(IdlStruct, typename="geometry_msgs::msg::dds_::WrenchStamped_"):
    header: Header = _of(Header)
    wrench: Wrench = _of(Wrench)


# sensor_msgs


@dataclass
class LaserScan(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    header: Header = _of(Header)
    angle_min: float32 = 0.0
    angle_max: float32 = 0.0
    angle_increment: float32 = 0.0
    time_increment: float32 = 0.0
    scan_time: float32 = 0.0
    range_min: float32 = 0.0
    range_max: float32 = 0.0
    ranges: types.sequence[float32] = _empty()
    intensities: types.sequence[float32] = _empty()


@dataclass
class Imu(IdlStruct, typename="sensor_msgs::msg::dds_::Imu_"):
    header: Header = _of(Header)
    orientation: Quaternion = _of(Quaternion)
    orientation_covariance: types.array[float64, 9] = _zeros(9)
    angular_velocity: Vector3 = _of(Vector3)
    angular_velocity_covariance: types.array[float64, 9] = _zeros(9)
    linear_acceleration: Vector3 = _of(Vector3)
    linear_acceleration_covariance: types.array[float64, 9] = _zeros(9)


@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header = _of(Header)
    name: types.sequence[str] = _empty()
    position: types.sequence[float64] = _empty()
    velocity: types.sequence[float64] = _empty()
    effort: types.sequence[float64] = _empty()


# nav_msgs


@dataclass
class MapMetaData(IdlStruct, typename="nav_msgs::msg::dds_::MapMetaData_"):
    map_load_time: Time = _of(Time)
    resolution: float32 = 0.0
    width: uint32 = 0
    height: uint32 = 0
    origin: Pose = _of(Pose)


@dataclass
class OccupancyGrid(IdlStruct, typename="nav_msgs::msg::dds_::OccupancyGrid_"):
    header: Header = _of(Header)
    info: MapMetaData = _of(MapMetaData)
    data: types.sequence[int8] = _empty()


@dataclass
class Path(IdlStruct, typename="nav_msgs::msg::dds_::Path_"):
    header: Header = _of(Header)
    poses: types.sequence[PoseStamped] = _empty()


@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    header: Header = _of(Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = _of(PoseWithCovariance)
    twist: TwistWithCovariance = _of(TwistWithCovariance)


# tf2_msgs


@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: types.sequence[TransformStamped] = _empty()


# rosgraph_msgs


@dataclass
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    clock: Time = _of(Time)


TYPES = {
    "builtin_interfaces/msg/Time": Time,
    "std_msgs/msg/Header": Header,
    "geometry_msgs/msg/Vector3": Vector3,
    "geometry_msgs/msg/Quaternion": Quaternion,
    "geometry_msgs/msg/Point": Point,
    "geometry_msgs/msg/Pose": Pose,
    "geometry_msgs/msg/Pose2D": Pose2D,
    "geometry_msgs/msg/PoseStamped": PoseStamped,
    "geometry_msgs/msg/PoseWithCovariance": PoseWithCovariance,
    "geometry_msgs/msg/Twist": Twist,
    "geometry_msgs/msg/TwistWithCovariance": TwistWithCovariance,
    "geometry_msgs/msg/Transform": Transform,
    "geometry_msgs/msg/TransformStamped": TransformStamped,
    "geometry_msgs/msg/Wrench": Wrench,
    "geometry_msgs/msg/WrenchStamped": WrenchStamped,
    "sensor_msgs/msg/LaserScan": LaserScan,
    "sensor_msgs/msg/Imu": Imu,
    "sensor_msgs/msg/JointState": JointState,
    "nav_msgs/msg/MapMetaData": MapMetaData,
    "nav_msgs/msg/OccupancyGrid": OccupancyGrid,
    "nav_msgs/msg/Path": Path,
    "nav_msgs/msg/Odometry": Odometry,
    "tf2_msgs/msg/TFMessage": TFMessage,
    "rosgraph_msgs/msg/Clock": Clock,
}


def to_dict(msg):
    """A message (or any value inside one) as plain JSON-able dicts, lists, numbers, strings."""
    if is_dataclass(msg) and not isinstance(msg, type):
        return {f.name: to_dict(getattr(msg, f.name)) for f in fields(msg)}
    if isinstance(msg, (bytes, bytearray)):
        return list(msg)
    if isinstance(msg, (list, tuple)):
        return [to_dict(v) for v in msg]
    if hasattr(msg, "tolist"):  # a numpy array or scalar
        return msg.tolist()
    return msg


def _is_float(hint):
    return hint is float or (typing.get_origin(hint) is typing.Annotated and hint.__origin__ is float)


def _field_kinds(cls):
    """Per field of an IDL class: (kind, struct class): kind struct, structs (a sequence or array
    of structs), floats, scalars (other sequences), float or scalar."""
    kinds = {}
    hints = typing.get_type_hints(cls, include_extras=True)
    for f in fields(cls):
        hint = hints[f.name]
        holder = None
        if typing.get_origin(hint) is typing.Annotated:
            holder = hint.__metadata__[0]
        if isinstance(holder, (types.array, types.sequence)):
            sub = holder.subtype
            if isinstance(sub, type) and is_dataclass(sub):
                kinds[f.name] = ("structs", sub)
            else:
                kinds[f.name] = ("floats" if _is_float(sub) else "scalars", None)
        elif isinstance(hint, type) and is_dataclass(hint):
            kinds[f.name] = ("struct", hint)
        elif _is_float(hint):
            kinds[f.name] = ("float", None)
        else:
            kinds[f.name] = ("scalar", None)
    return kinds


def from_dict(cls, data):
    """An instance of the IDL class ``cls`` from a dict like to_dict gives; missing fields are
    zero. Raises ValueError naming the field for an unknown field or a wrongly shaped value."""
    if data is None:
        return cls()
    if not isinstance(data, dict):
        raise ValueError(f"{cls.__name__}: expected an object, got {data!r}")
    kinds = _field_kinds(cls)
    unknown = set(data) - set(kinds)
    if unknown:
        raise ValueError(f"{cls.__name__}: unknown fields {sorted(unknown)}")
    values = {}
    for name, value in data.items():
        kind, sub = kinds[name]
        try:
            if kind == "struct":
                values[name] = from_dict(sub, value)
            elif kind in ("structs", "floats", "scalars"):
                if not isinstance(value, list):
                    raise ValueError(f"expected a list, got {value!r}")
                if kind == "structs":
                    values[name] = [from_dict(sub, v) for v in value]
                elif kind == "floats":
                    values[name] = [float(v) for v in value]
                else:
                    values[name] = list(value)
            elif kind == "float":
                values[name] = float(value)
            else:
                values[name] = value
        except (ValueError, TypeError) as e:
            raise ValueError(f"{cls.__name__}.{name}: {e}") from None
    msg = cls(**values)
    # Fixed-size arrays must have their exact length: catch it here with the field's name
    # rather than at serialization.
    hints = typing.get_type_hints(cls, include_extras=True)
    for name in values:
        hint = hints[name]
        if typing.get_origin(hint) is typing.Annotated:
            holder = hint.__metadata__[0]
            if isinstance(holder, types.array) and len(values[name]) != holder.length:
                raise ValueError(
                    f"{cls.__name__}.{name}: needs exactly {holder.length} elements, "
                    f"got {len(values[name])}"
                )
    return msg
