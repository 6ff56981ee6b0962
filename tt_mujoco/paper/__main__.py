"""``python -m tt_mujoco.paper``."""

from tt_mujoco import guard
from tt_mujoco.paper import main

guard.end(main())
