"""``python -m tt_mujoco.paper``."""

import sys

from tt_mujoco.paper import main

sys.exit(main())
