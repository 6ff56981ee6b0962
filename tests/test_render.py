"""Headless video rendering: the MP4 decodes, has the promised frames, shows the vehicle
where the time series puts it, and nothing is ever overwritten.

Videos are tiny (160x120, 2 s at 30 fps, a few seconds to render) and are decoded with the
ffmpeg binary of imageio-ffmpeg, as the renderer encodes with it.
"""

from __future__ import annotations

import json
import math

import imageio_ffmpeg
import mujoco
import numpy as np
import pytest

from tt_mujoco import render as render_cli
from tt_mujoco import runfolder
from tt_mujoco.sim.parts.terrain import parse_terrain
from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.params import Params
from tt_mujoco.viz import demo, gl, render

WIDTH, HEIGHT, FPS, DURATION = 160, 120, 30, 2.0


def SCENE(polyline):  # the tests' scene: the default vehicle on the path
    return render.RunScene(Params(), polyline)


def decode(path) -> tuple[dict, list[np.ndarray]]:
    frames = imageio_ffmpeg.read_frames(str(path))
    meta = next(frames)
    width, height = meta["size"]
    images = [np.frombuffer(f, np.uint8).reshape(height, width, 3) for f in frames]
    return meta, images


@pytest.fixture(scope="module")
def series():
    return demo.open_loop_timeseries(duration=DURATION, dt=0.01)


@pytest.fixture(scope="module")
def overview_video(series, tmp_path_factory):
    ts, polyline = series
    out = tmp_path_factory.mktemp("video") / "overview.mp4"
    try:
        render.render_video(
            ts,
            SCENE(polyline),
            out,
            render.VideoFormat(WIDTH, HEIGHT, FPS, "overview"),
            progress=False,
        )
    except render.RenderUnavailable as exc:  # a machine without any OpenGL: nothing to test
        pytest.skip(str(exc))
    return out


def test_video_decodes_with_promised_frames_and_size(overview_video):
    meta, frames = decode(overview_video)
    assert meta["codec"] == "h264"
    assert meta["size"] == (WIDTH, HEIGHT)
    # floor(duration * fps) + 1 frames: both ends of the run are shown.
    assert len(frames) == math.floor(DURATION * FPS) + 1 == 61
    assert all(f.shape == (HEIGHT, WIDTH, 3) for f in frames)


def test_frames_are_not_blank(overview_video):
    _, frames = decode(overview_video)
    # Measured: every frame's pixel std is ~42 (checker floor, vehicle, text); a blank or
    # single-colour frame has ~0, and the floor alone without lighting far less than 10.
    assert min(float(f.std()) for f in frames) > 10.0


def test_vehicle_is_where_the_series_puts_it_and_moves(series, overview_video):
    ts, polyline = series
    _, frames = decode(overview_video)
    first, last = frames[0].astype(float), frames[-1].astype(float)
    diff = np.abs(first - last).mean(axis=2)
    with render.RunRenderer(
        ts, SCENE(polyline), render.VideoFormat(WIDTH, HEIGHT, FPS, "overview")
    ) as r:
        fovy = float(r.model.vis.global_.fovy)
        camera = r.camera_at(0)  # the overview camera does not move
        start_i, end_i = r.index[0], r.index[-1]
    pixels = [
        render.project_to_pixel([ts["x"][i], ts["y"][i], 0.0], camera, fovy, WIDTH, HEIGHT)
        for i in (start_i, end_i)
    ]
    (c0, r0), (c1, r1) = [(round(c), round(r)) for c, r in pixels]
    # The vehicle drove ~1 m: its start and end images are far apart and inside the frame.
    assert math.hypot(c1 - c0, r1 - r0) > 20
    for c, r in ((c0, r0), (c1, r1)):
        assert 6 <= c < WIDTH - 6 and 30 <= r < HEIGHT - 6  # below the text overlay

    def window(c, r):
        return float(diff[r - 5 : r + 6, c - 5 : c + 6].mean())

    # Measured: 78 and 71 grey levels where the tractor left / arrived, exactly 0 in a floor
    # corner far from the vehicle, path and text (static background encodes identically).
    assert window(c0, r0) > 25.0
    assert window(c1, r1) > 25.0
    assert float(diff[100:118, 2:30].mean()) < 3.0


# 7 trace points keep every few committed frames, so most frames also draw a live segment pair.
@pytest.mark.parametrize("max_trace_points", [render.MAX_TRACE_POINTS, 7])
def test_reused_user_geoms_render_exactly_like_rebuilt_ones(series, monkeypatch, max_trace_points):
    monkeypatch.setattr(render, "MAX_TRACE_POINTS", max_trace_points)
    ts, polyline = series
    try:
        renderer = render.RunRenderer(
            ts, SCENE(polyline), render.VideoFormat(WIDTH, HEIGHT, FPS, "follow")
        )
    except render.RenderUnavailable as exc:
        pytest.skip(str(exc))
    with renderer as r:
        kept = r.trace_frames
        assert kept[0] == 0 and kept[-1] == r.n_frames - 1 and len(kept) <= max_trace_points
        assert np.all(np.diff(kept) > 0)
        sequential = {}
        for k in range(r.n_frames):
            image = r.render_frame(k)
            if k in (10, 45, r.n_frames - 1):
                sequential[k] = image.astype(int)
        # Rebuilding every user geom, and jumping back and forth in time, must give the same
        # pixels, up to MuJoCo's infinite floor plane: mjv_updateScene re-centres it under the
        # camera with some hysteresis (by one texture period, 2 m), which changes a few pixels
        # by one grey level (measured: 3 of 57600 values, by 1). A missing or stale trace
        # segment changes dozens of pixels by tens of levels.
        for k in (10, 45, r.n_frames - 1, 10, 45):
            for rewrite in (True, False):
                image = r.render_frame(k, rewrite=rewrite).astype(int)
                diff = np.abs(image - sequential[k])
                assert diff.max() <= 1
                assert np.count_nonzero(diff) <= 10


def _line_ends(geom) -> tuple[np.ndarray, np.ndarray]:
    """A connector line's end points: MuJoCo stores from-point, length and direction."""
    start = np.array(geom.pos)
    direction = np.array(geom.mat).reshape(3, 3)[:, 2]
    return start, start + geom.size[2] * direction


@pytest.mark.parametrize("max_trace_points", [render.MAX_TRACE_POINTS, 7])
def test_scene_draws_path_reference_point_and_traces_up_to_now(
    series, monkeypatch, max_trace_points
):
    monkeypatch.setattr(render, "MAX_TRACE_POINTS", max_trace_points)
    ts, polyline = series
    try:
        renderer = render.RunRenderer(
            ts, SCENE(polyline), render.VideoFormat(WIDTH, HEIGHT, FPS, "overview")
        )
    except render.RenderUnavailable as exc:
        pytest.skip(str(exc))
    with renderer as r:
        for frame in (0, 1, 30, 50, 31, 60, 22):  # forwards, backwards and jumps
            r.render_frame(frame)
            scene = r._off.scene
            geoms = scene.geoms[r._base : scene.ngeom]
            lines = [g for g in geoms if g.type == mujoco.mjtGeom.mjGEOM_LINE]
            path = [g for g in lines if np.allclose(g.rgba, render.PATH_RGBA)]
            assert len(path) == len(r.path) - 1
            # Each trace is a chain of segments from the first frame's point to this frame's.
            for colour, xy in (
                (render.TRACTOR_TRACE_RGBA, np.column_stack([ts["x"], ts["y"]])),
                (render.TRAILER_TRACE_RGBA, np.column_stack([ts["x0"], ts["y0"]])),
            ):
                ends = [_line_ends(g) for g in lines if np.allclose(g.rgba, colour)]
                # committed segments between kept frames before this one, then the live one
                assert len(ends) == np.searchsorted(r.trace_frames, frame)
                chain = [xy[r.index[0]]] + [b[:2] for _, b in ends]
                # MjvGeom stores float32: a point ~1 m from the origin is kept to ~6e-8 m and
                # an end rebuilt from length and direction to ~1e-7 m; a wrong frame is >1 mm off.
                for (a, _), previous in zip(ends, chain[:-1], strict=True):
                    np.testing.assert_allclose(a[:2], previous, atol=1e-6)
                np.testing.assert_allclose(chain[-1], xy[r.index[frame]], atol=1e-6)
            spheres = [g for g in geoms if g.type == mujoco.mjtGeom.mjGEOM_SPHERE]
            i = r.index[frame]
            np.testing.assert_allclose(
                spheres[0].pos[:2], [ts["x_ref"][i], ts["y_ref"][i]], atol=1e-6
            )


def test_pose_vehicle_puts_the_sites_at_P_and_P0():
    from tt_mujoco.sim.parts.physics import Vehicle

    p = Params(eta="paper")
    vehicle = Vehicle(p)
    x, y, theta, phi = 0.7, -0.3, 0.9, 0.25
    render.pose_vehicle(vehicle, x, y, theta, phi, p.eta * phi, np.zeros(4))
    _, P0, _ = reduced.trailer_pose(x, y, theta, phi, p)
    site = vehicle.data.site_xpos
    # mj_kinematics is exact up to float round-off; a wrong hitch sign moves P0 by ~0.2 m.
    np.testing.assert_allclose(site[vehicle.model.site("P").id][:2], [x, y], atol=1e-12)
    np.testing.assert_allclose(site[vehicle.model.site("P0").id][:2], P0, atol=1e-12)


def test_trailer_wheel_angles_roll_and_turn():
    p = Params()
    t = np.linspace(0.0, 2.0, 201)
    v0 = np.full_like(t, 0.5)
    theta0 = 0.3 * t  # turning left at 0.3 rad/s with beta = 0
    ts = {"t": t, "v0": v0, "theta0": theta0, "beta": np.zeros_like(t)}
    left, right = render.trailer_wheel_angles(ts, p)
    # (v0 t -+ (d/2) alpha) / r with alpha = 0.3 t; the trapezoid rule is exact for linear v0.
    np.testing.assert_allclose(left, (0.5 * t - 0.5 * p.d * 0.3 * t) / p.r, atol=1e-9)
    np.testing.assert_allclose(right, (0.5 * t + 0.5 * p.d * 0.3 * t) / p.r, atol=1e-9)


def test_a_diverged_run_is_shown_up_to_where_it_stopped(series):
    ts, polyline = series
    diverged = {name: np.array(col, dtype=float) for name, col in ts.items()}
    diverged["phi"][100:] = np.nan  # stopped after t = 0.99 s
    try:
        renderer = render.RunRenderer(
            diverged, SCENE(polyline), render.VideoFormat(WIDTH, HEIGHT, FPS)
        )
    except render.RenderUnavailable as exc:
        pytest.skip(str(exc))
    with renderer as r:
        assert r.n_frames == math.floor(0.99 * FPS) + 1 == 30
        assert r.render_frame(r.n_frames - 1).std() > 10.0


def test_frame_schedule_rounding_and_nearest_sample():
    t = np.arange(0, 201) * 0.01  # 2.00 s
    times, index = render.frame_schedule(t, 30)
    assert len(times) == 61 and times[-1] == pytest.approx(2.0)
    np.testing.assert_array_equal(index, np.round(times / 0.01).astype(int))
    assert len(render.frame_schedule(t[:200], 30)[0]) == 60  # 1.99 s: floor(59.7) + 1
    assert len(render.frame_schedule(np.array([0.0, 0.1]), 30)[0]) == 4  # 0.1 * 30 = 3.0000...04


def test_overview_camera_frames_every_point():
    points = np.array([[-3.0, 1.0], [5.0, 2.0], [0.0, -4.0], [1.0, 6.0]])
    for width, height in ((640, 480), (160, 120), (300, 600)):
        cam = render.overview_camera(points, 45.0, width / height)
        pix = np.array(
            [render.project_to_pixel([*q, 0.0], cam, 45.0, width, height) for q in points]
        )
        assert np.all((pix[:, 0] >= 0) & (pix[:, 0] <= width))
        assert np.all((pix[:, 1] >= 0) & (pix[:, 1] <= height))
        # Tight: some point is within 10 % of the frame's edge (margin 8 %).
        slack = np.minimum.reduce([pix[:, 0], width - pix[:, 0], pix[:, 1], height - pix[:, 1]])
        assert slack.min() < 0.1 * min(width, height)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"width": 161}, "width=161"),
        ({"height": 8}, "height=8"),
        ({"fps": 0}, "fps=0"),
        ({"camera": "chase"}, "camera='chase'"),
    ],
)
def test_bad_arguments_raise_value_error(series, tmp_path, kwargs, match):
    ts, polyline = series
    with pytest.raises(ValueError, match=match):
        render.render_video(
            ts, SCENE(polyline), tmp_path / "v.mp4", render.VideoFormat(**kwargs), progress=False
        )


def test_bad_series_raises_value_error(series, tmp_path):
    ts, polyline = series
    broken = dict(ts)
    del broken["phi"]
    with pytest.raises(ValueError, match="'phi'"):
        render.render_video(broken, SCENE(polyline), tmp_path / "v.mp4", progress=False)


def test_render_video_never_overwrites(series, tmp_path):
    ts, polyline = series
    out = tmp_path / "video.mp4"
    out.write_bytes(b"keep me")
    with pytest.raises(FileExistsError):
        render.render_video(
            ts, SCENE(polyline), out, render.VideoFormat(WIDTH, HEIGHT, FPS), progress=False
        )
    assert out.read_bytes() == b"keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["video.mp4"]  # no temporary left


def test_unknown_gl_backend_is_reported(monkeypatch):
    monkeypatch.setattr(gl, "_selected_backend", None)
    monkeypatch.setenv("MUJOCO_GL", "vulkan")
    with pytest.raises(render.RenderUnavailable, match="MUJOCO_GL='vulkan'"):
        render.select_gl_backend()


@pytest.fixture
def run_dir(tmp_path):
    """A finished run's folder: a 1 s series in timeseries.csv and its config."""
    p = Params()
    ts, _ = demo.open_loop_timeseries(p, duration=1.0, dt=0.02)
    names = list(ts)
    table = np.column_stack([ts[n] for n in names])
    folder = tmp_path / "run"
    folder.mkdir()
    np.savetxt(folder / "timeseries.csv", table, delimiter=",", header=",".join(names), comments="")
    config = {"params": p.to_dict(), "traj": "no_such_path_for_the_test"}
    (folder / "metrics.json").write_text(json.dumps({"rmse_v": 0.0, "config": config}))
    return folder


def test_cli_refuses_to_overwrite(run_dir, capsys):
    existing = run_dir.parent / "run.follow.mp4"  # the default: beside the run, by its camera
    existing.write_bytes(b"old video")
    assert render_cli.main([str(run_dir), "--no-progress"]) == 2
    assert "--out" in capsys.readouterr().err
    other = run_dir.parent / "other.mp4"
    other.write_bytes(b"other")
    assert render_cli.main([str(run_dir), "--out", str(other), "--no-progress"]) == 2
    assert existing.read_bytes() == b"old video" and other.read_bytes() == b"other"


@pytest.mark.parametrize("inside", ["video.mp4", "sub/video.mp4"])
def test_cli_never_writes_inside_the_run_folder(run_dir, capsys, inside):
    before = sorted(p.name for p in run_dir.iterdir())
    out = run_dir / inside
    assert render_cli.main([str(run_dir), "--out", str(out), "--no-progress"]) == 2
    assert "inside the run folder" in capsys.readouterr().err
    assert sorted(p.name for p in run_dir.iterdir()) == before


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--out", "video.txt"], "it must end in .mp4"),
        (["--height", "-5"], "height=-5 is not allowed"),
        (["--width", "7"], "width=7 is not allowed"),
        (["--fps", "nan"], "fps=nan is not allowed"),
    ],
)
def test_cli_bad_options_are_one_line_before_the_run_is_read(run_dir, capsys, args, says):
    if "--out" in args:
        args = ["--out", str(run_dir.parent / args[1])]
    before = sorted(p.name for p in run_dir.parent.iterdir())
    assert render_cli.main([str(run_dir), *args, "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and says in err[0], err
    assert sorted(p.name for p in run_dir.parent.iterdir()) == before


def test_cli_rerenders_a_run_to_a_new_file(run_dir):
    out = run_dir.parent / "small.mp4"
    argv = [str(run_dir), "--out", str(out), "--width", "64", "--height", "48", "--fps", "10"]
    code = render_cli.main([*argv, "--camera", "overview", "--no-progress"])
    if code == 1:
        pytest.skip("no OpenGL backend here")
    assert code == 0
    meta, frames = decode(out)
    assert meta["size"] == (64, 48)
    assert len(frames) == 11  # floor(1.0 s * 10 fps) + 1


def test_cli_rejects_a_folder_that_is_not_a_run(tmp_path, capsys):
    assert render_cli.main([str(tmp_path), "--no-progress"]) == 2
    assert "timeseries.csv" in capsys.readouterr().err


def test_params_from_config_round_trip_and_unknown_names():
    p = Params(eta="paper", Mf=10.0)
    assert runfolder.params_from_config(p.to_dict()) == p
    with pytest.raises(ValueError, match="wheelbase"):
        runfolder.params_from_config({"wheelbase": 1.0})


def _break(run_dir, how):
    csv = run_dir / "timeseries.csv"
    lines = csv.read_text().splitlines()
    if how == "cut":
        doc = json.loads((run_dir / "metrics.json").read_text())
        doc["steps"] = len(lines) - 1  # the run it claims
        (run_dir / "metrics.json").write_text(json.dumps(doc))
        csv.write_text("\n".join(lines[:20]) + "\n")  # cut at a line boundary
        return "the file is cut"
    if how == "nan":
        cells = lines[7].split(",")
        cells[1] = "nan"
        lines[7] = ",".join(cells)
        csv.write_text("\n".join(lines) + "\n")
        return "row 8 holds nan"
    (run_dir / "metrics.json").write_text("[]")
    return "is not a run's metrics"


@pytest.mark.parametrize("how", ["cut", "nan", "not metrics"])
def test_cli_refuses_a_broken_run_naming_what_is_wrong(run_dir, capsys, how):
    expected = _break(run_dir, how)
    code = render_cli.main([str(run_dir), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and expected in err and "Traceback" not in err
    assert not (run_dir.parent / "run.follow.mp4").exists()


def test_cli_out_the_file_system_refuses_is_exit_2(run_dir, capsys):
    code = render_cli.main([str(run_dir), "--out", "/proc/x.mp4", "--no-progress"])
    if code == 1:
        pytest.skip("no OpenGL backend here")
    assert code == 2 and "/proc/x.mp4" in capsys.readouterr().err


def test_osmesa_fallback_renders_when_egl_fails():
    # The real fallback, not its message: EGL's probe fails (as on a machine without EGL), so
    # the selection goes on to OSMesa, which must then render a frame. Needs libosmesa6 (CI
    # installs it where it can); skipped with the reason otherwise.
    import ctypes.util
    import os
    import subprocess
    import sys

    if ctypes.util.find_library("OSMesa") is None:
        pytest.skip("libOSMesa is not installed (Debian package libosmesa6)")
    code = (
        "from tt_mujoco.viz import gl\n"
        "gl._probe = lambda backend: 'EGL made to fail by the test' if backend == 'egl' else None\n"
        "print(gl.select_gl_backend())\n"
        "from tt_mujoco.viz.demo import open_loop_timeseries\n"
        "from tt_mujoco.viz.render import RunRenderer, RunScene, VideoFormat\n"
        "from tt_mujoco.vehicle.params import Params\n"
        "ts, poly = open_loop_timeseries(duration=0.5, dt=0.01)\n"
        "with RunRenderer(ts, RunScene(Params(), poly), VideoFormat(320, 240)) as r:\n"
        "    img = r.render_frame(10)\n"
        "print(img.shape, int(img.std() > 5))\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr[-1500:]
    assert proc.stdout.split() == ["osmesa", "(240,", "320,", "3)", "1"]


def _csv_run(tmp_path):
    """A finished CLI run on a CSV path (reduced plant, 2 s, no video)."""
    from tt_mujoco import run

    path = tmp_path / "path.csv"
    t = np.linspace(0.0, 1.0, 30)
    path.write_text("x,y\n" + "".join(f"{3 * v},{0.5 * math.sin(2 * v)}\n" for v in t))
    out = tmp_path / "run"
    argv = ["--traj", str(path), "--plant", "reduced", "--duration", "2", "--no-video"]
    assert run.main([*argv, "--no-plots", "--quiet", "--out", str(out)]) == 0
    return path, out


def test_render_draws_the_runs_own_path_after_its_csv_file_changed(tmp_path, capsys):
    # The run folder keeps the path it was given: editing (or deleting) the CSV file afterwards
    # changes nothing that render or compare draw.
    from tt_mujoco.outputs import REFERENCE_FILE, read_timeseries

    path, out = _csv_run(tmp_path)
    kept = read_timeseries(out / REFERENCE_FILE)
    path.write_text("x,y\n0,0\n1,1\n2,0\n3,1\n")
    polyline, source = runfolder.reference_polyline_for({}, out)
    assert source == f"the run's own {REFERENCE_FILE}"
    np.testing.assert_array_equal(polyline[:, 0], kept["x"])
    assert polyline[-1, 0] == pytest.approx(3.0, abs=0.05)  # the old path's end, x = 3 m
    path.unlink()
    assert runfolder.reference_polyline_for({}, out)[1] == source


def test_render_refuses_plant_params_edited_off_the_recorded_trace(tmp_path, capsys):
    from tt_mujoco.outputs import read_timeseries
    from tt_mujoco.sim import Scenario, simulate

    _, out = _csv_run(tmp_path)
    doc = json.loads((out / "metrics.json").read_text())
    ts = read_timeseries(out / "timeseries.parquet")
    as_run = runfolder.params_from_config(doc["config"]["plant_params"])
    assert runfolder.check_trace(as_run, ts) == ""
    mujoco_run = simulate(Scenario(duration=1.0, phi0_deg=10.0))  # contact physics: same rule
    assert runfolder.check_trace(Params(), mujoco_run.timeseries) == ""
    doc["config"]["plant_params"]["L"] *= 1.5
    (out / "metrics.json").write_text(json.dumps(doc))
    code = render_cli.main([str(out), "--no-progress", "--out", str(tmp_path / "v.mp4")])
    err = capsys.readouterr().err
    assert code == 2 and "are not the vehicle of its time series" in err, err
    assert not (tmp_path / "v.mp4").exists()
    series = demo.open_loop_timeseries(Params(), duration=1.0, dt=0.02)[0]
    assert runfolder.check_trace(Params(), series) == ""


def test_a_grade_is_drawn_as_a_slope_the_whole_scene_turned_alike(series):
    ts, polyline = series
    grade = "slope:20:90"  # rising along +y
    tilt = np.array(parse_terrain(grade).world_rotation)
    try:
        flat = render.RunRenderer(
            ts, SCENE(polyline), render.VideoFormat(WIDTH, HEIGHT, FPS, "overview")
        )
        sloped = render.RunRenderer(
            ts,
            render.RunScene(Params(), polyline, terrain=grade),
            render.VideoFormat(WIDTH, HEIGHT, FPS, "overview"),
        )
    except render.RenderUnavailable as exc:
        pytest.skip(str(exc))
    with flat as f, sloped as s:
        frame = 40
        image_flat, image_sloped = f.render_frame(frame), s.render_frame(frame)
        assert np.abs(image_flat.astype(int) - image_sloped.astype(int)).mean() > 5
        level, turned = f._off.scene, s._off.scene
        assert level.ngeom == turned.ngeom
        for a, b in zip(level.geoms[: level.ngeom], turned.geoms[: turned.ngeom], strict=True):
            if a.type == mujoco.mjtGeom.mjGEOM_LINE:  # the path and traces: their ends turned
                for end_a, end_b in zip(_line_ends(a), _line_ends(b), strict=True):
                    np.testing.assert_allclose(tilt @ end_a, end_b, atol=1e-5)
                continue
            # Every body, the floor included, at the turned place and orientation (float32).
            np.testing.assert_allclose(tilt @ a.pos, b.pos, atol=1e-5)
            if a.type != mujoco.mjtGeom.mjGEOM_SPHERE:  # a sphere has no orientation to keep
                np.testing.assert_allclose(
                    tilt @ a.mat.reshape(3, 3), b.mat.reshape(3, 3), atol=1e-5
                )
        floor = next(
            g for g in turned.geoms[: turned.ngeom] if g.type == mujoco.mjtGeom.mjGEOM_PLANE
        )
        a = math.radians(20)
        np.testing.assert_allclose(
            floor.mat.reshape(3, 3)[:, 2], [0, -math.sin(a), math.cos(a)], atol=1e-6
        )


def test_lines_drawn_as_chords_within_the_tolerance_look_as_every_segment_does(series, monkeypatch):
    # The path and the traces are drawn as chords within DRAW_TOLERANCE (1 mm) of the curve:
    # 35 line segments here instead of 320, and the same picture. Where two aliased one-pixel
    # lines lie on each other (the tractor's and the trailer's traces), a chord that lands one
    # pixel over flips which colour is on top: measured 4 of the 19,200 pixels at most. (That
    # every committed chord is in place is test_scene_draws_path_reference_point_and_traces_...)
    ts, polyline = series
    frames, default = {}, render.DRAW_TOLERANCE
    for tolerance in (default, 0.0):
        monkeypatch.setattr(render, "DRAW_TOLERANCE", tolerance)
        try:
            renderer = render.RunRenderer(
                ts, SCENE(polyline), render.VideoFormat(WIDTH, HEIGHT, FPS, "follow")
            )
        except render.RenderUnavailable as exc:
            pytest.skip(str(exc))
        with renderer as r:
            n_user = len(r.path) - 1 + 2 * (len(r.trace_frames) - 1)  # line segments, last frame
            frames[tolerance] = n_user, [r.render_frame(k).astype(int) for k in (20, 40, 60)]
    (simple, drawn), (every, exact) = frames[default], frames[0.0]
    assert simple < every / 4
    for a, b in zip(drawn, exact, strict=True):
        changed = np.count_nonzero(np.abs(a - b).max(axis=2) > 8)
        assert changed <= 0.002 * WIDTH * HEIGHT, changed
