"""``python -m tt_mujoco.model``: write the MJCF, scene and URDF of the vehicle into ``models/``."""

from __future__ import annotations

import argparse
import sys

from tt_mujoco.vehicle.mjcf import write_models


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tt_mujoco.model",
        description="Regenerate models/ (MJCF, scene and URDF) from Params().",
    )
    parser.parse_args(argv)
    for path in write_models():
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
