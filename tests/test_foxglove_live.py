"""The live view in Foxglove (tt_mujoco.viz.foxglove_live): a Foxglove client that connects
is told the channels and receives the run's frames; the command refuses what cannot run."""

import asyncio
import json
import socket

import pytest

pytest.importorskip("foxglove")
websockets = pytest.importorskip("websockets")

from tt_mujoco import run  # noqa: E402
from tt_mujoco.sim import Scenario  # noqa: E402
from tt_mujoco.sim.parts.measure import Measurement  # noqa: E402
from tt_mujoco.viz.foxglove_live import FoxgloveLive  # noqa: E402
from tt_mujoco.world.builtin import parse_world  # noqa: E402


class _Plant:
    def __init__(self, x):
        self.x = x

    def measure(self):
        return Measurement(self.x, 0.5, 0.1, 0.05, 0.0, 0.8, 0.1, *([0.0] * 12))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


async def _client(port: int, live: FoxgloveLive):
    url = f"ws://127.0.0.1:{port}"
    async with websockets.connect(url, subprotocols=["foxglove.sdk.v1"]) as ws:
        info = json.loads(await asyncio.wait_for(ws.recv(), 5))
        advertised = json.loads(await asyncio.wait_for(ws.recv(), 5))
        channels = {c["topic"]: c for c in advertised["channels"]}
        subscriptions = [{"id": i, "channelId": c["id"]} for i, c in enumerate(channels.values())]
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
        await asyncio.sleep(0.2)
        for k in range(3):
            live(k * 0.1, _Plant(float(k)))
        frames = []
        while len(frames) < 5:
            frame = await asyncio.wait_for(ws.recv(), 5)
            if isinstance(frame, bytes):
                frames.append(frame)
        return info, channels, frames


def test_a_client_is_told_the_channels_and_gets_the_runs_frames():
    params = Scenario().plant_params()
    live = FoxgloveLive(
        params, [[0.0, 0.0], [1.0, 0.0], [2.0, 0.5]], parse_world("loading_bay"), port=0,
        realtime=False,
    )  # fmt: skip
    try:
        info, channels, frames = asyncio.run(_client(live.port, live))
    finally:
        live.close()
    assert info["op"] == "serverInfo"
    assert channels["/tf"]["schemaName"] == "foxglove.FrameTransforms"
    assert channels["/scene"]["schemaName"] == "foxglove.SceneUpdate"
    assert channels["/reference"]["schemaName"] == "foxglove.PosesInFrame"
    assert channels["/state"]["encoding"] == "json"
    assert all(frame[0] == 1 for frame in frames)  # message data (the protocol's opcode 1)


def test_the_command_serves_a_run_and_refuses_what_cannot_run(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    base = ["--plant", "reduced", "--duration", "0.5", "--no-video", "--no-plots", "--quiet"]
    port = _free_port()
    assert run.main([*base, "--live", str(port), "--no-live-realtime", "--out", "a"]) == 0
    assert (tmp_path / "a" / "metrics.json").is_file()
    assert "live" not in (tmp_path / "a" / "config.toml").read_text()  # how it was watched
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        busy = taken.getsockname()[1]
        assert run.main([*base, "--live", str(busy), "--out", "b"]) == 2
    assert "--live" in capsys.readouterr().err
    assert not (tmp_path / "b").exists()
    assert run.main([*base, "--live", "70000", "--out", "c"]) == 2
    assert "'70000' is not allowed" in capsys.readouterr().err
