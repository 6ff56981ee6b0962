"""``python -m tt_mujoco.sweep``."""

from tt_mujoco import guard
from tt_mujoco.sweep import main

guard.end(main())
