"""Worlds: the obstacles a train must not touch and the goal it drives to.

- :mod:`tt_mujoco.world.world`: the world's objects, read from a TOML file and checked;
- :mod:`tt_mujoco.world.builtin`: the named worlds and the reader of ``Scenario.world``;
- :mod:`tt_mujoco.world.contact`: the plain-number contact check the step runs;
- :mod:`tt_mujoco.world.part`: the world as the step's part (its record, its checks before the
  run, its report after it);
- :mod:`tt_mujoco.world.mjcf`: the obstacles as the MuJoCo scene's collision geoms.
"""
