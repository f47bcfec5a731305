#!/usr/bin/env python3
"""ROS 2 messages read and written by an independent type system (the `rosbags` package, not this project's
encoder), for tests/tests/ros2_interop.rs.

    rosbags_check.py hashes [TYPE...]     JSON {type: RIHS01 hash}; without TYPE, the 8 types of ros2::types::ALL
    rosbags_check.py decode TYPE FILE...  one JSON object per FILE (a CDR payload with its 4-byte encapsulation
                                          header, as rmw_zenoh carries it), one per line
    rosbags_check.py encode TYPE          JSON of a message on stdin -> its CDR bytes (header included) on stdout

JSON form of a message: nested messages are objects, arrays and sequences are lists, except that uint8 / byte /
char arrays and sequences are lowercase hex strings; floats are strings holding Python's repr (shortest round-trip
form, so a reader parses them exactly; also covers nan and inf, which JSON numbers cannot). `encode` takes the
same form, and also accepts floats as JSON numbers and byte arrays as lists of integers.

The typestore is rosbags' ROS 2 Jazzy store, plus the types it lacks, registered here from their .msg definitions:
vision_msgs 4.x (ros-perception/vision_msgs, branch ros2), event_camera_msgs (ros-event-camera/event_camera_msgs,
msg_ros2/EventPacket.msg) and std_srvs/srv/Trigger. Comments do not enter a type hash, so the definitions below
leave them out; none of these messages has constants.

Errors (unknown type, unreadable file, bytes that are not the type, bad JSON): a message on stderr, exit code 2.
"""

from __future__ import annotations

import json
import sys

try:
    import numpy as np
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    from rosbags.typesys.base import Nodetype
except ImportError as e:  # pragma: no cover - depends on the machine
    sys.stderr.write(
        f"rosbags_check: {e}: the independent ROS 2 type system (rosbags) is not installed for {sys.executable}; "
        "install it with `bash .ci/setup` (pip install rosbags==0.11.9)\n"
    )
    sys.exit(2)

# The types of ros2::types::ALL (ros2/src/types.rs), in its order.
ALL_TYPES = [
    "geometry_msgs/msg/PoseStamped",
    "tf2_msgs/msg/TFMessage",
    "vision_msgs/msg/Detection3DArray",
    "diagnostic_msgs/msg/DiagnosticArray",
    "event_camera_msgs/msg/EventPacket",
    "sensor_msgs/msg/Image",
    "sensor_msgs/msg/CameraInfo",
    "std_srvs/srv/Trigger",
]

# vision_msgs 4.1.1 (branch ros2), comments left out.
VISION_MSGS = {
    "vision_msgs/msg/Detection3DArray": "std_msgs/Header header\nDetection3D[] detections\n",
    "vision_msgs/msg/Detection3D": (
        "std_msgs/Header header\nObjectHypothesisWithPose[] results\nBoundingBox3D bbox\nstring id\n"
    ),
    "vision_msgs/msg/ObjectHypothesisWithPose": (
        "ObjectHypothesis hypothesis\ngeometry_msgs/PoseWithCovariance pose\n"
    ),
    "vision_msgs/msg/ObjectHypothesis": "string class_id\nfloat64 score\n",
    "vision_msgs/msg/BoundingBox3D": "geometry_msgs/Pose center\ngeometry_msgs/Vector3 size\n",
}

# event_camera_msgs, msg_ros2/EventPacket.msg, comments left out.
EVENT_CAMERA_MSGS = {
    "event_camera_msgs/msg/EventPacket": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nuint64 seq\nuint64 time_base\n"
        "string encoding\nbool is_bigendian\nuint8[] events\n"
    ),
}

# std_srvs/srv/Trigger as rosidl expands a service: request, response, the event message, and the service type
# whose three fields are those (its type hash covers all of them).
STD_SRVS = {
    "std_srvs/srv/Trigger_Request": "uint8 structure_needs_at_least_one_member\n",
    "std_srvs/srv/Trigger_Response": "bool success\nstring message\n",
    "std_srvs/srv/Trigger_Event": (
        "service_msgs/ServiceEventInfo info\n"
        "std_srvs/srv/Trigger_Request[<=1] request\n"
        "std_srvs/srv/Trigger_Response[<=1] response\n"
    ),
    "std_srvs/srv/Trigger": (
        "std_srvs/srv/Trigger_Request request_message\n"
        "std_srvs/srv/Trigger_Response response_message\n"
        "std_srvs/srv/Trigger_Event event_message\n"
    ),
}

# rosbags declares client_gid as char[16] (as the .msg does); rosidl's type description, which the hash is taken
# over, has uint8 for char. The byte layout is the same.
SERVICE_EVENT_INFO = (
    "service_msgs/msg/ServiceEventInfo",
    "uint8 REQUEST_SENT = 0\nuint8 REQUEST_RECEIVED = 1\nuint8 RESPONSE_SENT = 2\nuint8 RESPONSE_RECEIVED = 3\n"
    "uint8 event_type\nbuiltin_interfaces/Time stamp\nuint8[16] client_gid\nint64 sequence_number\n",
)

BYTE_TYPES = {"uint8", "byte", "char", "int8"}
FLOAT_TYPES = {"float32", "float64"}
INT_TYPES = {"int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "byte", "char"}
NUMPY_DTYPES = {
    "bool": np.bool_,
    "byte": np.uint8,
    "char": np.uint8,
    "int8": np.int8,
    "uint8": np.uint8,
    "int16": np.int16,
    "uint16": np.uint16,
    "int32": np.int32,
    "uint32": np.uint32,
    "int64": np.int64,
    "uint64": np.uint64,
    "float32": np.float32,
    "float64": np.float64,
}


class CheckError(Exception):
    """A usage or input error: reported on stderr with exit code 2."""


def _fix_srv_names(obj):
    """get_types_from_msg names `std_srvs/srv/X` as `std_srvs/srv/msg/X` (in keys and nested references)."""
    if isinstance(obj, str):
        return obj.replace("std_srvs/srv/msg/", "std_srvs/srv/")
    if isinstance(obj, tuple):
        return tuple(_fix_srv_names(x) for x in obj)
    if isinstance(obj, list):
        return [_fix_srv_names(x) for x in obj]
    if isinstance(obj, dict):
        return {_fix_srv_names(k): _fix_srv_names(v) for k, v in obj.items()}
    return obj


def make_typestore():
    store = get_typestore(Stores.ROS2_JAZZY)
    # Replace rosbags' ServiceEventInfo (char[16] client_gid) by rosidl's view of it (uint8[16]); register()
    # refuses a changed definition, so the old one goes first.
    name, text = SERVICE_EVENT_INFO
    store.fielddefs.pop(name, None)
    store.types.pop(name, None)
    store.register(get_types_from_msg(text, name))
    for defs in (VISION_MSGS, EVENT_CAMERA_MSGS):
        typs = {}
        for name, text in defs.items():
            typs.update(get_types_from_msg(text, name))
        store.register(typs)
    typs = {}
    for name, text in STD_SRVS.items():
        typs.update(get_types_from_msg(text, name))
    store.register(_fix_srv_names(typs))
    return store


def _check_type(store, typename):
    if typename not in store.fielddefs:
        raise CheckError(f"unknown type {typename!r} (known: e.g. {', '.join(ALL_TYPES)})")


# --- message -> JSON -------------------------------------------------------------------------------------------


def _base_to_json(typ, value):
    if typ in FLOAT_TYPES:
        return repr(float(value))
    if typ == "bool":
        return bool(value)
    if typ == "string":
        return str(value)
    return int(value)


def _field_to_json(store, desc, value):
    kind, rest = desc
    if kind == Nodetype.BASE:
        return _base_to_json(rest[0], value)
    if kind == Nodetype.NAME:
        return msg_to_json(store, rest, value)
    # ARRAY or SEQUENCE: rest is (element desc, bound).
    elem = rest[0]
    if elem[0] == Nodetype.BASE and elem[1][0] in BYTE_TYPES - {"int8"}:
        return bytes(np.asarray(value, dtype=np.uint8)).hex()
    return [_field_to_json(store, elem, v) for v in value]


def msg_to_json(store, typename, msg):
    out = {}
    for fname, desc in store.fielddefs[typename][1]:
        out[fname] = _field_to_json(store, desc, getattr(msg, fname))
    return out


# --- JSON -> message -------------------------------------------------------------------------------------------


def _base_from_json(typ, value, where):
    try:
        if typ in FLOAT_TYPES:
            if isinstance(value, bool):
                raise TypeError("a bool is not a float")
            return float(value)
        if typ == "bool":
            if not isinstance(value, bool):
                raise TypeError(f"expected true or false, got {value!r}")
            return value
        if typ == "string":
            if not isinstance(value, str):
                raise TypeError(f"expected a string, got {value!r}")
            return value
        if typ in INT_TYPES:
            if isinstance(value, bool) or not isinstance(value, int):
                raise TypeError(f"expected an integer, got {value!r}")
            return value
    except (TypeError, ValueError) as e:
        raise CheckError(f"{where}: {e}") from None
    raise CheckError(f"{where}: unsupported type {typ}")


def _field_from_json(store, desc, value, where):
    kind, rest = desc
    if kind == Nodetype.BASE:
        return _base_from_json(rest[0], value, where)
    if kind == Nodetype.NAME:
        return msg_from_json(store, rest, value, where)
    elem, bound = rest
    if elem[0] == Nodetype.BASE and elem[1][0] in BYTE_TYPES - {"int8"} and isinstance(value, str):
        try:
            items = list(bytes.fromhex(value))
        except ValueError:
            raise CheckError(f"{where}: not a hex string") from None
    elif isinstance(value, list):
        items = value
    else:
        raise CheckError(f"{where}: expected a list")
    if kind == Nodetype.ARRAY and len(items) != bound:
        raise CheckError(f"{where}: {len(items)} elements, the array has {bound}")
    if kind == Nodetype.SEQUENCE and bound and len(items) > bound:
        raise CheckError(f"{where}: {len(items)} elements, the sequence allows {bound}")
    values = [_field_from_json(store, elem, v, f"{where}[{i}]") for i, v in enumerate(items)]
    if elem[0] == Nodetype.BASE and elem[1][0] in NUMPY_DTYPES:
        # rosbags keeps arrays of primitives as numpy arrays.
        return np.array(values, dtype=NUMPY_DTYPES[elem[1][0]])
    return values


def msg_from_json(store, typename, obj, where=""):
    if not isinstance(obj, dict):
        raise CheckError(f"{where or typename}: expected an object")
    fields = store.fielddefs[typename][1]
    names = {f for f, _ in fields}
    extra = set(obj) - names
    if extra:
        raise CheckError(f"{where or typename}: unknown fields {sorted(extra)} (fields: {[f for f, _ in fields]})")
    kwargs = {}
    for fname, desc in fields:
        path = f"{where}.{fname}" if where else fname
        if fname not in obj:
            raise CheckError(f"{path}: missing")
        kwargs[fname] = _field_from_json(store, desc, obj[fname], path)
    return store.types[typename](**kwargs)


# --- commands --------------------------------------------------------------------------------------------------


def cmd_hashes(store, args):
    names = args or ALL_TYPES
    for n in names:
        _check_type(store, n)
    print(json.dumps({n: store.hash_rihs01(n) for n in names}, indent=1))


def cmd_decode(store, args):
    if len(args) < 2:
        raise CheckError("usage: decode TYPE FILE...")
    typename, files = args[0], args[1:]
    _check_type(store, typename)
    for path in files:
        try:
            with open(path, "rb") as f:
                raw = f.read()
        except OSError as e:
            raise CheckError(f"cannot read {path}: {e}") from None
        try:
            msg = store.deserialize_cdr(raw, typename)
        except Exception as e:  # rosbags raises several kinds for bad bytes
            raise CheckError(f"{path}: not a CDR {typename}: {type(e).__name__}: {e}") from None
        print(json.dumps(msg_to_json(store, typename, msg)))


def cmd_encode(store, args):
    if len(args) != 1:
        raise CheckError("usage: encode TYPE < message.json")
    typename = args[0]
    _check_type(store, typename)
    try:
        obj = json.load(sys.stdin)
    except json.JSONDecodeError as e:
        raise CheckError(f"stdin is not JSON: {e}") from None
    msg = msg_from_json(store, typename, obj)
    try:
        raw = store.serialize_cdr(msg, typename)
    except Exception as e:
        raise CheckError(f"rosbags cannot serialize this {typename}: {type(e).__name__}: {e}") from None
    sys.stdout.buffer.write(bytes(raw))
    sys.stdout.buffer.flush()


COMMANDS = {"hashes": cmd_hashes, "decode": cmd_decode, "encode": cmd_encode}


def main(argv):
    if len(argv) < 2 or argv[1] not in COMMANDS:
        sys.stderr.write(__doc__)
        return 2
    try:
        COMMANDS[argv[1]](make_typestore(), argv[2:])
    except CheckError as e:
        sys.stderr.write(f"rosbags_check: {e}\n")
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
