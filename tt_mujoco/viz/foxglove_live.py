"""``--live PORT``: the running simulation served to Foxglove over its WebSocket protocol
(optional extra: ``pip install tt-mujoco[mcap]``, which brings ``foxglove-sdk``).

Open Foxglove, connect to ``ws://localhost:PORT``: its 3D panel shows each unit's frame
(``/tf``, ``foxglove.FrameTransforms``) and footprint, the obstacles and the goal
(``/scene``, ``foxglove.SceneUpdate``) and the reference path (``/reference``,
``foxglove.PosesInFrame``); its plots take ``/state`` (``v``, ``omega``, each hitch angle, in
JSON). The server listens on the local address only. By default the run is paced to real time
(``--no-live-realtime``: as fast as it runs); the scene and the path are sent again every second
for a client that connects late. A run without ``--live`` imports nothing of this.
"""

from __future__ import annotations

import json
import math
import time

import numpy as np

__all__ = ["LIVE_RATE", "FoxgloveLive", "LiveError"]

#: Messages per second of simulated time sent to Foxglove.
LIVE_RATE = 30.0
#: Every this many seconds of wall time the static scene and path are sent again.
RESEND_S = 1.0


class LiveError(RuntimeError):
    """The live view cannot start: no foxglove-sdk, or the port is taken."""


def _quaternion(heading: float):
    from foxglove.messages import Quaternion

    return Quaternion(x=0.0, y=0.0, z=math.sin(heading / 2.0), w=math.cos(heading / 2.0))


class FoxgloveLive:
    """``on_step`` hook (see :func:`tt_mujoco.sim.simulate`) serving the run to Foxglove."""

    def __init__(self, params, reference, world=None, port: int = 8765, realtime: bool = True):
        try:
            import foxglove
            from foxglove.channels import (
                FrameTransformsChannel,
                PosesInFrameChannel,
                SceneUpdateChannel,
            )
        except ImportError as err:
            raise LiveError("--live needs foxglove-sdk: pip install 'tt-mujoco[mcap]'") from err
        self.context = foxglove.Context()
        try:
            self.server = foxglove.start_server(
                name="tt-mujoco", host="127.0.0.1", port=int(port), context=self.context
            )
        except Exception as err:  # the SDK's own error type: a port in use, say
            raise LiveError(f"--live {port}: the server cannot start: {err}") from err
        self.port = self.server.port
        self.tf = FrameTransformsChannel("/tf", context=self.context)
        self.scene = SceneUpdateChannel("/scene", context=self.context)
        self.path = PosesInFrameChannel("/reference", context=self.context)
        self.state = foxglove.Channel("/state", message_encoding="json", context=self.context)
        self.params, self.world = params, world
        self.reference = np.asarray(reference, dtype=float)
        self.realtime = realtime
        self._next_t, self._began, self._sent_static = 0.0, None, -math.inf

    def __call__(self, t: float, plant) -> None:
        if t + 1e-12 < self._next_t:
            return
        self._next_t = t + 1.0 / LIVE_RATE
        now = time.monotonic()
        if self._began is None:
            self._began = now - t
        if self.realtime and self._began + t > now:
            time.sleep(self._began + t - now)
        ns = round(t * 1e9)
        if time.monotonic() - self._sent_static >= RESEND_S:
            self._send_static(ns)
            self._sent_static = time.monotonic()
        self._send_state(plant.measure(), ns)

    def _units(self, m):
        """Each unit's frame and pose ``(x, y, heading)`` from a measurement."""
        units = [("tractor", m.x, m.y, m.theta), ("trailer_1", m.x0, m.y0, m.theta0)]
        for k, row in enumerate(getattr(m, "train", ()), start=2):
            units.append((f"trailer_{k}", row[0], row[1], row[2]))
        return units

    def _send_state(self, m, ns: int) -> None:
        from foxglove.messages import FrameTransform, FrameTransforms, Vector3

        transforms = [
            FrameTransform(
                parent_frame_id="world",
                child_frame_id=frame,
                translation=Vector3(x=float(x), y=float(y), z=0.0),
                rotation=_quaternion(float(heading)),
            )
            for frame, x, y, heading in self._units(m)
        ]
        self.tf.log(FrameTransforms(transforms=transforms), log_time=ns)
        phis = [float(p) for p in getattr(m, "phis", (m.phi,))]
        state = {"v": float(m.v), "omega": float(m.omega), "phi": phis}
        self.state.log(json.dumps(state).encode(), log_time=ns)

    def _send_static(self, ns: int) -> None:
        from foxglove.messages import (
            Color,
            CubePrimitive,
            LinePrimitive,
            LinePrimitiveLineType,
            Point3,
            Pose,
            PosesInFrame,
            SceneEntity,
            SceneUpdate,
            Vector3,
        )

        from tt_mujoco.vehicle.footprint import footprints

        entities = []
        for k, (rear, front, half) in enumerate(footprints(self.params)):
            frame = "tractor" if k == 0 else f"trailer_{k}"
            cube = CubePrimitive(
                pose=Pose(
                    position=Vector3(x=(rear + front) / 2.0, y=0.0, z=0.1),
                    orientation=_quaternion(0.0),
                ),
                size=Vector3(x=front - rear, y=2.0 * half, z=0.2),
                color=Color(r=0.2, g=0.5, b=0.9, a=0.8),
            )
            entities.append(SceneEntity(frame_id=frame, id=frame, cubes=[cube]))
        if self.world is not None:  # each obstacle's outline, as the contact check sees it
            for o, corners in enumerate(self.world.polygons(footprints(self.params)[-1])):
                outline = LinePrimitive(
                    type=LinePrimitiveLineType.LineLoop,
                    pose=Pose(position=Vector3(x=0.0, y=0.0, z=0.0), orientation=_quaternion(0.0)),
                    thickness=0.03,
                    scale_invariant=False,
                    points=[Point3(x=float(x), y=float(y), z=0.0) for x, y in corners],
                    color=Color(r=0.8, g=0.3, b=0.2, a=1.0),
                )
                entities.append(
                    SceneEntity(frame_id="world", id=f"obstacle_{o + 1}", lines=[outline])
                )
        self.scene.log(SceneUpdate(entities=entities), log_time=ns)
        steps = np.diff(self.reference, axis=0)
        headings = np.arctan2(steps[:, 1], steps[:, 0])
        poses = [
            Pose(position=Vector3(x=float(x), y=float(y), z=0.0), orientation=_quaternion(float(h)))
            for (x, y), h in zip(self.reference[:-1], headings, strict=False)
        ]
        self.path.log(PosesInFrame(frame_id="world", poses=poses), log_time=ns)

    def close(self) -> None:
        server, self.server = getattr(self, "server", None), None
        if server is not None:
            server.stop()

    def wait_closed(self) -> None:
        """At the end of the run: the server stops (Foxglove keeps what it received)."""
        self.close()
