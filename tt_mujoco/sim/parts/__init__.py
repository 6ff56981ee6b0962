"""The simulated physical parts, each owning its formulas and its record's fields: the plants
(``plant``, ``plant_mujoco``, ``plant_reduced``, ``physics``), the sensors (``measure``), the
disturbances, faults, ground, motors, wind, terrain and relief, and the trailers' steering
(``schedule``). The step (:mod:`tt_mujoco.sim.loop.closed_loop`) composes them; none imports
the loop."""
