"""Runs as MCAP files of ROS 2 messages (tt_mujoco.bag): every topic with its ROS 2 schema and
its count, the values the run's own, read back by the mcap readers without ROS; the command's
bad input is exit 2 with nothing written."""

import json
import math

import numpy as np
import pytest
from documents import key_paths, nested, parent_of
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

pytest.importorskip("mcap_ros2")

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from tt_mujoco import bag, run
from tt_mujoco.outputs import read_timeseries
from tt_mujoco.runfolder import default_out
from tt_mujoco.world.builtin import parse_world


@pytest.fixture(scope="module")
def bay_run(tmp_path_factory):
    """A planned run into the loading bay, two trailers, written with --mcap."""
    folder = tmp_path_factory.mktemp("bag") / "run"
    code = run.main(
        [
            *("--world", "loading_bay", "--traj", "plan", "--reverse", "--seed", "1"),
            *("--trailers", "2", "--plant", "reduced", "--no-video", "--no-plots"),
            *("--quiet", "--mcap", "--out", str(folder)),
        ]
    )
    assert code == 0
    return folder


def _read(path):
    with open(path, "rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        channels = {
            c.topic: (
                summary.schemas[c.schema_id].name,
                summary.statistics.channel_message_counts[c.id],
            )
            for c in summary.channels.values()
        }
        messages = {}
        for _, channel, message, decoded in reader.iter_decoded_messages():
            messages.setdefault(channel.topic, []).append((message.log_time, decoded))
    return channels, messages


def test_every_topic_has_its_ros2_schema_and_count(bay_run):
    channels, _ = _read(bay_run / bag.BAG_FILE)
    ts = read_timeseries(bay_run / "timeseries.parquet")
    rows = len(range(0, len(ts["t"]), round(1.0 / (bag.DEFAULT_RATE * 0.001))))
    expected = {
        "/tf": "tf2_msgs/msg/TFMessage",
        "/tractor/odom": "nav_msgs/msg/Odometry",
        "/trailer_1/odom": "nav_msgs/msg/Odometry",
        "/trailer_2/odom": "nav_msgs/msg/Odometry",
        "/joint_states": "sensor_msgs/msg/JointState",
        "/reference/point": "geometry_msgs/msg/PoseStamped",
        "/tracking_errors": "std_msgs/msg/Float64MultiArray",
    }
    for topic, schema in expected.items():
        assert channels[topic] == (schema, rows), topic
    assert channels["/reference/path"] == ("nav_msgs/msg/Path", 1)
    assert channels["/world/goal"] == ("geometry_msgs/msg/PoseStamped", 1)
    obstacles = len(parse_world("loading_bay").all_obstacles)
    assert sorted(t for t in channels if t.startswith("/world/obstacle_")) == sorted(
        f"/world/obstacle_{k}" for k in range(1, obstacles + 1)
    )


def test_the_messages_hold_the_runs_values(bay_run):
    _, messages = _read(bay_run / bag.BAG_FILE)
    ts = read_timeseries(bay_run / "timeseries.parquet")
    stride = round(1.0 / (bag.DEFAULT_RATE * 0.001))
    for j in (0, 7, len(messages["/tf"]) - 1):
        i = j * stride
        log_time, odom = messages["/trailer_2/odom"][j]
        assert log_time == round(ts["t"][i] * 1e9)
        assert odom.pose.pose.position.x == ts["x0_2"][i]
        assert odom.pose.pose.position.y == ts["y0_2"][i]
        q = odom.pose.pose.orientation
        assert 2 * math.atan2(q.z, q.w) == pytest.approx(ts["theta0_2"][i], abs=1e-12)
        assert odom.twist.twist.linear.x == ts["v0_2"][i]
        _, joints = messages["/joint_states"][j]
        assert joints.name[:2] == ["hitch_1", "hitch_2"]
        assert joints.position[0] == ts["phi"][i] and joints.position[1] == ts["phi_2"][i]
        assert joints.effort[-2:] == [ts["T_r"][i], ts["T_l"][i]]
        _, tf = messages["/tf"][j]
        assert [t.child_frame_id for t in tf.transforms] == ["tractor", "trailer_1", "trailer_2"]
        assert tf.transforms[0].transform.translation.x == ts["x"][i]
        _, errors = messages["/tracking_errors"][j]
        labels = [d.label for d in errors.layout.dim]
        assert labels[:2] == ["e_v", "e_omega"]
        assert errors.data[0] == pytest.approx(ts["v"][i] - ts["v_d"][i], abs=1e-15)
    _, path = messages["/reference/path"][0]
    line = read_timeseries(bay_run / "reference_path.parquet")
    assert len(path.poses) == len(line["x"])
    assert path.poses[-1].pose.position.x == line["x"][-1]
    goal = parse_world("loading_bay").goal
    _, pose = messages["/world/goal"][0]
    assert (pose.pose.position.x, pose.pose.position.y) == (goal.x, goal.y)


def test_the_command_converts_a_run_once(bay_run, capsys):
    out = bay_run.parent / "again.mcap"
    assert bag.main([str(bay_run), "--out", str(out), "--rate", "10"]) == 0
    channels, _ = _read(out)
    ts = read_timeseries(bay_run / "timeseries.parquet")
    assert channels["/tf"][1] == len(range(0, len(ts["t"]), 100))
    assert bag.main([str(bay_run), "--out", str(out)]) == 2
    assert "never overwritten" in capsys.readouterr().err
    inside = bay_run / "again.mcap"
    assert bag.main([str(bay_run), "--out", str(inside)]) == 2
    assert "inside the run folder" in capsys.readouterr().err and not inside.exists()


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--rate", "0"], "rate=0.0"),
        (["--rate", "nan"], "rate=nan"),
    ],
)
def test_bad_input_is_exit_2_and_writes_nothing(bay_run, tmp_path, capsys, args, says):
    out = tmp_path / "x.mcap"
    assert bag.main([str(bay_run), "--out", str(out), *args]) == 2
    assert says in capsys.readouterr().err
    assert not out.exists() and not list(tmp_path.iterdir())


@pytest.mark.parametrize("name", ["x.txt", "x", "x.mcap.part"])
def test_an_out_file_not_named_mcap_is_refused(bay_run, tmp_path, capsys, name):
    # Foxglove and the mcap tools know the file by its name
    assert bag.main([str(bay_run), "--out", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "it must end in .mcap" in err[0], err
    assert not list(tmp_path.iterdir())


def test_a_folder_that_is_not_a_run_is_refused(tmp_path, capsys):
    (tmp_path / "metrics.json").write_text(json.dumps({"status": "ok"}))
    (tmp_path / "timeseries.csv").write_text("t\n0\n")
    assert bag.main([str(tmp_path)]) == 2
    assert "not a run's metrics" in capsys.readouterr().err
    assert not default_out(tmp_path, "ros2", ".mcap").exists()
    assert bag.main([str(tmp_path / "missing")]) == 2


def test_mcap_without_the_extra_is_refused_before_the_run(tmp_path, monkeypatch, capsys):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util,
        "find_spec",
        lambda name, *a: None if name == "mcap_ros2" else real(name, *a),
    )
    monkeypatch.chdir(tmp_path)
    code = run.main(["--plant", "reduced", "--duration", "0.5", "--mcap", "--out", "o", "--quiet"])
    assert code == 2 and "mcap extra" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_every_schema_names_only_types_it_defines():
    for name in bag.MESSAGES:
        text = bag.schema_text(name)
        defined = {
            line.removeprefix("MSG: ") for line in text.splitlines() if line.startswith("MSG: ")
        }
        for line in text.splitlines():
            words = line.split()
            if words and "/" in words[0] and not line.startswith("MSG: "):
                assert words[0].split("[")[0] in defined, (name, line)
    assert np.isfinite(bag.DEFAULT_RATE)


@pytest.mark.parametrize(
    ("edit", "says"),
    [
        (lambda doc: doc["config"].update(scenario=[1, 2]), "config.scenario"),
        (lambda doc: doc["config"]["scenario"].update(world=3), "config.scenario"),
        (lambda doc: doc["config"].update(plant_params="L"), "config.plant_params"),
        (lambda doc: doc["config"]["scenario"].update(world="gone.toml"), "gone.toml"),
    ],
)
def test_an_edited_run_folder_is_one_message(bay_run, tmp_path, capsys, edit, says):
    import shutil

    folder = tmp_path / "edited"
    shutil.copytree(bay_run, folder, ignore=shutil.ignore_patterns("*.mcap"))
    doc = json.loads((folder / "metrics.json").read_text())
    edit(doc)
    if says == "gone.toml":  # a run from before runs kept their world
        (folder / "world.toml").unlink()
    (folder / "metrics.json").write_text(json.dumps(doc))
    assert bag.main([str(folder)]) == 2
    err = capsys.readouterr().err
    assert says in err and len(err.strip().splitlines()) == 1, err
    assert not default_out(folder, "ros2", ".mcap").exists()


def test_a_time_series_without_a_column_is_one_message(bay_run, tmp_path, capsys):
    import shutil

    from tt_mujoco.outputs import write_timeseries

    folder = tmp_path / "cut"
    shutil.copytree(bay_run, folder, ignore=shutil.ignore_patterns("*.mcap"))
    ts = read_timeseries(folder / "timeseries.parquet")
    del ts["theta_l"]
    (folder / "timeseries.parquet").unlink()
    write_timeseries(folder / "timeseries.parquet", ts, list(ts))
    assert bag.main([str(folder)]) == 2
    assert "theta_l" in capsys.readouterr().err


def test_a_run_keeps_its_world_and_converts_without_the_file(tmp_path, monkeypatch):
    """The run keeps the world it ran in (world.toml): the conversion reads that copy, so a
    world file edited or gone since changes nothing."""
    import copy

    import tomli_w

    from tt_mujoco.world.builtin import KEPT_WORLD, WORLDS
    from tt_mujoco.world.world import read_world, world_from_table

    monkeypatch.chdir(tmp_path)
    table = copy.deepcopy(WORLDS["loading_bay"])
    table["start"] = {"x": 2.0, "y": -1.0, "heading_deg": 180.0}
    (tmp_path / "mine.toml").write_text(tomli_w.dumps(table))
    code = run.main(
        [
            *("--world", "mine.toml", "--traj", "plan", "--reverse", "--plant", "reduced"),
            *("--no-video", "--no-plots", "--quiet", "--out", "r"),
        ]
    )
    assert code == 0
    kept = read_world(tmp_path / "r" / KEPT_WORLD)
    assert kept == world_from_table(table, "mine")
    (tmp_path / "mine.toml").unlink()
    assert bag.main(["r"]) == 0
    channels, _ = _read(tmp_path / "r.ros2.mcap")  # beside the run: a reader writes outside it
    assert channels["/world/goal"][1] == 1


_JSON = nested(
    st.none() | st.booleans() | st.integers(-(10**9), 10**9) | st.floats() | st.text(max_size=6),
    key_size=5,
    max_leaves=6,
)


@settings(
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_an_edited_metrics_json_is_converted_or_refused_in_one_line(
    bay_run, tmp_path_factory, data
):
    """metrics.json with any value put anywhere under config: exit 0 or exit 2 with one line,
    never a bug of ours (exit 70)."""
    import shutil

    folder = tmp_path_factory.mktemp("edited") / "run"
    shutil.copytree(bay_run, folder, ignore=shutil.ignore_patterns("*.mcap", "*.parquet"))
    shutil.copy(bay_run / "timeseries.parquet", folder / "timeseries.parquet")
    shutil.copy(bay_run / "reference_path.parquet", folder / "reference_path.parquet")
    doc = json.loads((folder / "metrics.json").read_text())
    path = data.draw(st.sampled_from(list(key_paths(doc["config"], ("config",), depth=3))))
    parent_of(doc, path)[path[-1]] = data.draw(_JSON)
    (folder / "metrics.json").write_text(json.dumps(doc))
    code = bag.main([str(folder), "--rate", "2"])
    assert code in (0, 2), path
