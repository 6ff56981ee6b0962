"""What an install ships: every package folder of the source is a package pyproject.toml names
(an editable install finds a forgotten one anyway; a wheel would leave it out)."""

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_every_package_folder_is_named_in_pyproject():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    named = set(config["packages"])
    folders = {
        ".".join(path.parent.relative_to(ROOT).parts)
        for path in (ROOT / "tt_mujoco").rglob("__init__.py")
    }
    folders |= {"tt_mujoco.controllers"}  # the top-level controllers/, installed under tt_mujoco
    assert config["package-dir"]["tt_mujoco.controllers"] == "controllers"
    assert named == folders, (sorted(folders - named), sorted(named - folders))
