"""The live viewer: refused cleanly without a display; with one (a stand-in window here) it
follows the same closed loop that writes the outputs."""

import json
import os
import subprocess
import sys
from contextlib import contextmanager
from types import SimpleNamespace

import mujoco
import mujoco.viewer
import pytest

from tt_mujoco import run
from tt_mujoco.viz import viewer


def test_no_display_exits_2_without_traceback(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    proc = subprocess.run(
        [sys.executable, "-m", "tt_mujoco.run", "--viewer", "--duration", "1", "--quiet"],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        cwd=tmp_path,
    )
    assert proc.returncode == 2, proc.stderr
    assert "--viewer needs a display" in proc.stderr
    assert "DISPLAY" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []  # no renders/ folder


class FakeWindow:
    """Stands in for ``mujoco.viewer.Handle``: counts syncs; the "user" closes the window
    after ``close_after`` of them."""

    def __init__(self, model, close_after=None):
        self.cam = SimpleNamespace(type=None, trackbodyid=-1, distance=0.0, elevation=0.0)
        self.user_scn = mujoco.MjvScene(model, maxgeom=1000)
        self.syncs = 0
        self.close_after = close_after
        self.closed = False

    @contextmanager
    def lock(self):
        yield

    def is_running(self):
        return not self.closed and self.syncs < self.close_after

    def sync(self):
        self.syncs += 1

    def close(self):
        self.closed = True


@pytest.fixture
def fake_display(monkeypatch):
    windows = []

    def launch(model, data, close_after=None, **kwargs):
        windows.append(FakeWindow(model, close_after=monkeypatch.close_after))
        return windows[-1]

    monkeypatch.close_after = 30
    monkeypatch.setenv("DISPLAY", ":99")
    monkeypatch.setattr(viewer, "_probe_display", lambda advice: None)
    monkeypatch.setattr(mujoco.viewer, "launch_passive", launch)
    return monkeypatch, windows


def test_viewer_follows_the_run_live(tmp_path, fake_display):
    monkeypatch, windows = fake_display
    monkeypatch.close_after = 30  # closed right after the last frame (else it waits for the user)
    out = tmp_path / "run"
    code = run.main(
        ["--viewer", "--duration", "0.5", "--no-video", "--no-plots", "--out", str(out)]
    )
    assert code == 0
    (window,) = windows
    # 60 refreshes per simulated second over 0.5 s (the first at the first step).
    assert window.syncs == 30
    assert window.cam.type == mujoco.mjtCamera.mjCAMERA_TRACKING
    assert window.user_scn.ngeom > 50  # the reference path is drawn
    assert window.closed
    assert json.loads((out / "metrics.json").read_text())["status"] == "ok"


def test_closing_the_viewer_abandons_the_run(tmp_path, fake_display, capsys):
    monkeypatch, _ = fake_display
    monkeypatch.close_after = 6  # the user closes the window after 0.1 s
    out = tmp_path / "run"
    code = run.main(["--viewer", "--duration", "1", "--no-video", "--no-plots", "--out", str(out)])
    assert code == run.EXIT_INTERRUPTED
    err = capsys.readouterr().err
    assert "viewer closed at t=0.1" in err and "nothing was written" in err
    assert not out.exists()
