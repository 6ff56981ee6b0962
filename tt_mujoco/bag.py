"""A run as an MCAP file of ROS 2 messages (optional extra: ``pip install tt-mujoco[mcap]``).

``python -m tt_mujoco.bag RUN_DIR`` converts a finished run's folder; ``--mcap`` (the TOML key
``mcap``) writes ``run.mcap`` with a run's other outputs. The file opens in Foxglove with no
configuration (its 3D panel draws the frames, the paths, the obstacles; its plots take any
field) and in ROS 2's bag tools (``ros2 bag info``, ``ros2 bag play``: the messages are CDR
with their ROS 2 definitions), and the ``mcap`` readers read it without ROS.

Topics (frame ``world``; each unit's frame is its axle's middle, x forward):

- ``/tf`` (``tf2_msgs/msg/TFMessage``): world -> ``tractor``, world -> ``trailer_k``.
- ``/tractor/odom``, ``/trailer_k/odom`` (``nav_msgs/msg/Odometry``): each unit's pose and its
  speed along its heading; the tractor's yaw rate.
- ``/joint_states`` (``sensor_msgs/msg/JointState``): ``hitch_k`` (phi_k), ``axle_k`` (beta_k,
  the trailer axle's steering angle), ``wheel_right``/``wheel_left`` (angle, rate, torque).
- ``/reference/path`` (``nav_msgs/msg/Path``, once), ``/reference/point``
  (``geometry_msgs/msg/PoseStamped``): the path and the reference point.
- ``/tracking_errors`` (``std_msgs/msg/Float64MultiArray``, its dimension labels naming the
  values): ``e_v``, ``e_omega``, ``cross_track``, ``along_track``, ``trailer_cross_track`` as
  ``metrics.json`` measures them (:func:`tt_mujoco.analysis.metrics.error_signals`).
- ``/world/goal`` (``geometry_msgs/msg/PoseStamped``) and ``/world/obstacle_k``
  (``geometry_msgs/msg/PolygonStamped``), once, for a run in a world.

Rows are written at ``rate`` (Hz; the run's own rate at most), each at its simulated time.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from tt_mujoco import guard
from tt_mujoco.cliargs import Parser
from tt_mujoco.outputs import publish_new, temporary_beside
from tt_mujoco.runfolder import check_out, default_out, read_run

__all__ = [
    "BAG_FILE",
    "DEFAULT_RATE",
    "LOG_TOPICS",
    "MESSAGES",
    "main",
    "read_bag_log",
    "write_bag",
]

#: The file a run writes (``--mcap``) and the command writes by default.
BAG_FILE = "run.mcap"
#: Rows per second written (Hz): Foxglove's plots and 3D panel need no more.
DEFAULT_RATE = 50.0

_RULE = "=" * 80
#: The ROS 2 definitions of every message written and of those they hold (as ROS 2's
#: ``rosidl`` gives them, the dependencies in the order the schema texts list them).
_DEFS = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Point32": "float32 x\nfloat32 y\nfloat32 z",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
    "geometry_msgs/Pose": "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation",
    "geometry_msgs/PoseWithCovariance": "geometry_msgs/Pose pose\nfloat64[36] covariance",
    "geometry_msgs/Twist": "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular",
    "geometry_msgs/TwistWithCovariance": "geometry_msgs/Twist twist\nfloat64[36] covariance",
    "geometry_msgs/Transform": (
        "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation"
    ),
    "geometry_msgs/TransformStamped": (
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform"
    ),
    "geometry_msgs/PoseStamped": "std_msgs/Header header\ngeometry_msgs/Pose pose",
    "geometry_msgs/Polygon": "geometry_msgs/Point32[] points",
    "geometry_msgs/PolygonStamped": "std_msgs/Header header\ngeometry_msgs/Polygon polygon",
    "std_msgs/MultiArrayDimension": "string label\nuint32 size\nuint32 stride",
    "std_msgs/MultiArrayLayout": "std_msgs/MultiArrayDimension[] dim\nuint32 data_offset",
    "std_msgs/Float64MultiArray": "std_msgs/MultiArrayLayout layout\nfloat64[] data",
    "nav_msgs/Odometry": (
        "std_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist"
    ),
    "nav_msgs/Path": "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses",
    "sensor_msgs/JointState": (
        "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n"
        "float64[] effort"
    ),
    "tf2_msgs/TFMessage": "geometry_msgs/TransformStamped[] transforms",
}
#: The messages written, by topic kind.
MESSAGES = (
    "tf2_msgs/TFMessage",
    "nav_msgs/Odometry",
    "sensor_msgs/JointState",
    "nav_msgs/Path",
    "geometry_msgs/PoseStamped",
    "std_msgs/Float64MultiArray",
    "geometry_msgs/PolygonStamped",
)


def _dependencies(name: str, seen: list[str]) -> list[str]:
    """Every type ``name`` holds, depth first, each once."""
    for line in _DEFS[name].splitlines():
        kind = line.split()[0].split("[")[0]
        if "/" in kind and kind not in seen:
            seen.append(kind)
            _dependencies(kind, seen)
    return seen


def schema_text(name: str) -> str:
    """The ``ros2msg`` schema of ``name``: its fields, then each type it holds."""
    parts = [_DEFS[name]]
    for kind in _dependencies(name, []):
        parts += [_RULE, f"MSG: {kind}", _DEFS[kind]]
    return "\n".join(parts) + "\n"


def _ros2_name(name: str) -> str:
    package, kind = name.split("/")
    return f"{package}/msg/{kind}"


def _stamp(t: float) -> dict:
    ns = round(t * 1e9)
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def _header(t: float, frame: str = "world") -> dict:
    return {"stamp": _stamp(t), "frame_id": frame}


def _pose(x: float, y: float, heading: float) -> dict:
    return {
        "position": {"x": x, "y": y, "z": 0.0},
        "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(heading / 2), "w": math.cos(heading / 2)},
    }


def _units(ts: dict, n: int) -> list[tuple[str, str, str, str, str]]:
    """Each unit's frame and its columns ``(x, y, heading, speed)``."""
    units = [("tractor", "x", "y", "theta", "v")]
    for k in range(1, n + 1):
        suffix = "" if k == 1 else f"_{k}"
        units.append(
            (f"trailer_{k}", f"x0{suffix}", f"y0{suffix}", f"theta0{suffix}", f"v0{suffix}")
        )
    return units


def _error_columns(ts: dict, polyline: np.ndarray, reverse: bool) -> dict[str, np.ndarray]:
    from tt_mujoco.analysis.metrics import error_signals

    signals = error_signals(ts, polyline, reverse)
    out = {"e_v": signals["e_v"], "e_omega": signals["e_omega"]}
    out["cross_track"] = signals["cross_track"]
    out["along_track"] = signals["along_track"]
    out["trailer_cross_track"] = signals["trailer_lateral"]
    return out


def write_bag(
    ts: dict,
    polyline: np.ndarray,
    params,
    out: Path,
    reverse: bool = False,
    world=None,
    rate: float = DEFAULT_RATE,
) -> Path:
    """Write a run's time series ``ts`` (its columns), its reference ``polyline``, its
    vehicle's ``params`` and its world (:class:`tt_mujoco.world.World` or None) as ``out``,
    an MCAP file of ROS 2 messages (see the module); atomically, never over an existing file.

    Raises
    ------
    FileExistsError
        ``out`` exists.
    ValueError
        ``rate`` is not a positive number.
    """
    try:
        from mcap_ros2.writer import Writer
    except ImportError as err:
        raise ImportError(
            "writing MCAP needs the mcap extra: pip install 'tt-mujoco[mcap]'"
        ) from err
    if not (isinstance(rate, int | float) and math.isfinite(rate) and rate > 0):
        raise ValueError(f"rate={rate!r} is not allowed: give a positive number (Hz)")
    t = np.asarray(ts["t"], dtype=float)
    period = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    stride = max(1, round(1.0 / (rate * period)))
    rows = _RowMessages(ts, polyline, params.n_trailers, reverse)
    with temporary_beside(out, ".mcap.tmp") as partial:
        with open(partial, "wb") as stream:
            writer = Writer(stream)
            schemas = {
                name: writer.register_msgdef(_ros2_name(name), schema_text(name))
                for name in MESSAGES
            }

            def write(topic: str, kind: str, message: dict, at: float) -> None:
                ns = round(at * 1e9)
                writer.write_message(topic, schemas[kind], message, log_time=ns, publish_time=ns)

            start = float(t[0]) if t.size else 0.0
            write("/reference/path", "nav_msgs/Path", _path_message(polyline, start), start)
            if world is not None:
                _write_world(write, world, params, start)
            for i in range(0, t.size, stride):
                for topic, kind, message in rows.messages(i):
                    write(topic, kind, message, float(t[i]))
            writer.finish()
        return publish_new(partial, out)


def _path_message(polyline: np.ndarray, start: float) -> dict:
    """The reference path as a ``nav_msgs/Path``, each pose facing along it."""
    poses = [{"header": _header(start), "pose": _pose(x, y, 0.0)} for x, y in polyline]
    for pose, heading in zip(poses, _headings(polyline), strict=True):
        pose["pose"]["orientation"] = _pose(0.0, 0.0, heading)["orientation"]
    return {"header": _header(start), "poses": poses}


class _RowMessages:
    """The messages of one row of a run's time series: every unit's odometry and transform,
    the joints, the reference point and the tracking errors."""

    def __init__(self, ts: dict, polyline: np.ndarray, n_trailers: int, reverse: bool):
        self.ts = ts
        t = np.asarray(ts["t"], dtype=float)
        self.errors = _error_columns(ts, polyline, reverse) if t.size else {}
        self.wheel_rates = [
            np.gradient(ts[c], t) if t.size > 1 else np.zeros(t.size)
            for c in ("theta_r", "theta_l")
        ]
        self.units = _units(ts, n_trailers)
        hitches = range(1, n_trailers + 1)
        self.joints = [f"hitch_{k}" for k in hitches] + [f"axle_{k}" for k in hitches]
        self.joints += ["wheel_right", "wheel_left"]
        self.angles = [f"phi{'' if k == 1 else f'_{k}'}" for k in hitches]
        self.angles += [f"beta{'' if k == 1 else f'_{k}'}" for k in hitches]

    def messages(self, i: int):
        """``(topic, message type, message)`` of row ``i``, in the order written."""
        ts, at = self.ts, float(self.ts["t"][i])
        transforms = []
        for frame, x, y, heading, speed in self.units:
            pose = _pose(float(ts[x][i]), float(ts[y][i]), float(ts[heading][i]))
            transform = {"translation": pose["position"], "rotation": pose["orientation"]}
            transforms.append(
                {"header": _header(at), "child_frame_id": frame, "transform": transform}
            )
            yaw_rate = float(ts["omega"][i]) if frame == "tractor" else 0.0
            twist = {
                "linear": {"x": float(ts[speed][i]), "y": 0.0, "z": 0.0},
                "angular": {"x": 0.0, "y": 0.0, "z": yaw_rate},
            }
            odometry = {
                "header": _header(at),
                "child_frame_id": frame,
                "pose": {"pose": pose, "covariance": [0.0] * 36},
                "twist": {"twist": twist, "covariance": [0.0] * 36},
            }
            yield f"/{frame}/odom", "nav_msgs/Odometry", odometry
        yield "/tf", "tf2_msgs/TFMessage", {"transforms": transforms}
        yield "/joint_states", "sensor_msgs/JointState", self._joint_state(i, at)
        if "theta_ref" in ts:
            reference = _pose(
                float(ts["x_ref"][i]), float(ts["y_ref"][i]), float(ts["theta_ref"][i])
            )
            pose_stamped = {"header": _header(at), "pose": reference}
            yield "/reference/point", "geometry_msgs/PoseStamped", pose_stamped
        labels = list(self.errors)
        layout = {
            "dim": [{"label": name, "size": 1, "stride": 1} for name in labels],
            "data_offset": 0,
        }
        data = [float(self.errors[name][i]) for name in labels]
        yield "/tracking_errors", "std_msgs/Float64MultiArray", {"layout": layout, "data": data}

    def _joint_state(self, i: int, at: float) -> dict:
        ts = self.ts
        angles = [float(ts[c][i]) for c in self.angles]
        return {
            "header": _header(at),
            "name": self.joints,
            "position": [*angles, float(ts["theta_r"][i]), float(ts["theta_l"][i])],
            "velocity": [math.nan] * len(angles)
            + [float(self.wheel_rates[0][i]), float(self.wheel_rates[1][i])],
            "effort": [math.nan] * len(angles) + [float(ts["T_r"][i]), float(ts["T_l"][i])],
        }


#: The topics a log in MCAP is read from by default (what :func:`write_bag` writes, and what a
#: ROS 2 vehicle commonly records): the tractor's odometry and the joint states.
LOG_TOPICS = {"odom": "/tractor/odom", "joints": "/joint_states"}


def _stamped(path, topic: str, rows: list) -> None:
    """A topic's messages ``rows`` (``((stamp, log time), ...)``) on their times: its header
    stamps, or its log times where it stamps none (all zero), in place; at least two, each
    after the last (a ValueError naming the topic and the message otherwise)."""
    if len(rows) < 2:
        raise ValueError(f"{path}: topic {topic!r} has {len(rows)} message(s): too few")
    use_stamps = any(row[0][0] > 0.0 for row in rows)
    rows[:] = [(at[0] if use_stamps else 1e-9 * at[1], *rest) for at, *rest in rows]
    stamps = np.array([row[0] for row in rows])
    back = np.flatnonzero(np.diff(stamps) <= 0.0)
    if back.size:
        k = int(back[0]) + 1
        raise ValueError(
            f"{path}: topic {topic!r} message {k + 1}'s stamp {float(stamps[k])!r} does not "
            f"come after message {k}'s {float(stamps[k - 1])!r}"
        )


def read_bag_log(path, topics: dict[str, str] | None = None) -> dict[str, np.ndarray]:
    """A vehicle's log from an MCAP file of ROS 2 messages, as columns on the odometry's times.

    ``t`` (s), ``v`` (m/s) and ``omega`` (rad/s) are the ``nav_msgs/msg/Odometry`` of
    ``topics["odom"]`` (its header stamps, or its log times where a topic stamps none; its
    twist's linear x and angular z); every joint of the ``sensor_msgs/msg/JointState`` of
    ``topics["joints"]`` is a column named as the joint (``hitch_1``, ... as :func:`write_bag`
    names them), its positions interpolated linearly at the odometry's times (which are kept
    only within the joints' span: two topics at their own rates, with samples dropped, read
    alike).

    Raises
    ------
    ValueError
        Naming the file and the topic, the joint or the message: not an MCAP file, a topic
        absent or of another type, a stamp that does not increase, a value that is not a
        finite number.
    """
    import struct

    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    chosen = {**LOG_TOPICS, **(topics or {})}
    wanted = {
        chosen["odom"]: "nav_msgs/msg/Odometry",
        chosen["joints"]: "sensor_msgs/msg/JointState",
    }
    odom, joints = [], []
    try:
        with open(path, "rb") as stream:
            reader = make_reader(stream, decoder_factories=[DecoderFactory()])
            summary = reader.get_summary()
            if summary is None:
                raise ValueError(f"{path} has no summary: it is cut or not a finished MCAP file")
            found = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
            for topic, kind in wanted.items():
                if topic not in found:
                    raise ValueError(
                        f"{path} has no topic {topic!r} ({kind}); its topics: {sorted(found)}"
                    )
                if found[topic] != kind:
                    raise ValueError(f"{path}: topic {topic!r} holds {found[topic]}, not {kind}")
            for _, channel, message, msg in reader.iter_decoded_messages(topics=list(wanted)):
                at = (msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec, message.log_time)
                if channel.topic == chosen["odom"]:
                    odom.append((at, msg.twist.twist.linear.x, msg.twist.twist.angular.z))
                else:
                    joints.append((at, list(msg.name), list(msg.position), list(msg.effort)))
    except (McapError, OSError, EOFError, KeyError, AttributeError, struct.error) as err:
        raise ValueError(f"{path} cannot be read as MCAP of ROS 2 messages: {err}") from None
    for topic, rows in ((chosen["odom"], odom), (chosen["joints"], joints)):
        _stamped(path, topic, rows)
    table = {"t": np.array([r[0] for r in odom]), "v": np.array([r[1] for r in odom])}
    table["omega"] = np.array([r[2] for r in odom])
    for name in ("v", "omega"):
        bad = np.flatnonzero(~np.isfinite(table[name]))
        if bad.size:
            raise ValueError(
                f"{path}: topic {chosen['odom']!r} message {int(bad[0]) + 1} has {name} = "
                f"{float(table[name][bad[0]])!r}, not a finite number"
            )
    joint_t = np.array([r[0] for r in joints])
    keep = (table["t"] >= joint_t[0]) & (table["t"] <= joint_t[-1])
    table = {name: column[keep] for name, column in table.items()}
    names = joints[0][1]
    for k, (_, these, positions, _) in enumerate(joints):
        if these != names or len(positions) != len(names):
            raise ValueError(
                f"{path}: topic {chosen['joints']!r} message {k + 1} names the joints "
                f"{these}, not {names} as the first does"
            )
    positions = np.array([r[2] for r in joints], dtype=float)
    for j, name in enumerate(names):
        column = positions[:, j]
        if np.all(np.isnan(column)):
            continue  # a joint the log does not give a position of
        bad = np.flatnonzero(~np.isfinite(column))
        if bad.size:
            raise ValueError(
                f"{path}: topic {chosen['joints']!r} message {int(bad[0]) + 1} has joint "
                f"{name!r} at {float(column[bad[0]])!r}, not a finite number"
            )
        table[name] = np.interp(table["t"], joint_t, column)
    efforts = [r[3] for r in joints]
    if all(len(e) == len(names) for e in efforts):  # a joint's effort, each held till the next
        efforts = np.array(efforts, dtype=float)
        held = np.clip(np.searchsorted(joint_t, table["t"], side="right") - 1, 0, None)
        for j, name in enumerate(names):
            if np.all(np.isfinite(efforts[:, j])):
                table[f"{name}_effort"] = efforts[held, j]
    return table


def _headings(polyline: np.ndarray) -> np.ndarray:
    """The heading along a polyline at each vertex (the last segment's at the end)."""
    if len(polyline) < 2:
        return np.zeros(len(polyline))
    d = np.diff(polyline, axis=0)
    headings = np.arctan2(d[:, 1], d[:, 0])
    return np.append(headings, headings[-1])


def _write_world(write, world, params, at: float) -> None:
    """The world's goal and obstacles, once."""
    from tt_mujoco.vehicle.footprint import footprints

    goal = world.goal
    if goal is not None:
        pose = _pose(goal.x, goal.y, math.radians(goal.heading_deg))
        write("/world/goal", "geometry_msgs/PoseStamped", {"header": _header(at), "pose": pose}, at)
    for k, corners in enumerate(world.polygons(footprints(params)[-1]), start=1):
        points = [{"x": float(x), "y": float(y), "z": 0.0} for x, y in corners]
        write(
            f"/world/obstacle_{k}",
            "geometry_msgs/PolygonStamped",
            {"header": _header(at), "polygon": {"points": points}},
            at,
        )


@guard.command
def main(argv: list[str] | None = None) -> int:
    """``python -m tt_mujoco.bag RUN_DIR``: write a finished run as an MCAP file.

    Exit codes: 0 written; 2 bad input (not a run's folder, the file exists, no mcap extra).
    """
    parser = Parser(
        prog="python -m tt_mujoco.bag",
        description="Write a finished run (RUN_DIR/timeseries.parquet or .csv, metrics.json) "
        "as an MCAP file of ROS 2 messages, for Foxglove and ROS 2's bag tools. Never "
        "overwrites a file.",
    )
    parser.add_argument("run_dir", type=Path, metavar="RUN_DIR")
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help="a new file outside the run folder (default: RUN_DIR.ros2.mcap beside it)",
    )
    parser.add_argument(
        "--rate",
        type=float,
        default=DEFAULT_RATE,
        help=f"rows per second (default {DEFAULT_RATE:g})",
    )
    args = parser.parse_args(argv)

    def fail(message: str) -> int:
        print(f"error: {message}", file=sys.stderr)
        return 2

    run_dir: Path = args.run_dir
    out = args.out if args.out is not None else default_out(run_dir, "ros2", ".mcap")
    try:
        if out.exists() or out.is_symlink():
            return fail(f"{out} exists and is never overwritten; name a new file with --out FILE")
        check_out(out, ".mcap")
        run = read_run(run_dir)
        reverse = bool(run.scenario.get("reverse"))
        write_bag(run.timeseries, run.reference, run.params, out, reverse, run.world, args.rate)
    except (ValueError, KeyError, ImportError, FileExistsError) as err:
        return fail(str(err))
    except OSError as err:
        return fail(f"{out}: {err.strerror}")
    print(out)
    return 0


if __name__ == "__main__":
    guard.end(main())
