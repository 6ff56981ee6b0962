"""``python -m tt_mujoco.sweep``."""

import sys

from tt_mujoco.sweep import main

sys.exit(main())
