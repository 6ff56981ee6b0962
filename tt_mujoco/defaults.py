"""Project-wide defaults and limits, in one place (SI units, degrees where named so).

The vehicle's physical parameters and their defaults (the paper's Section 6.1) are the fields of
:class:`tt_mujoco.vehicle.params.Params`; the controllers' gain presets are on their classes.
Everything else a run falls back on is here.
"""

from __future__ import annotations

#: Physics timestep (s): the contact and coupling time constants are two steps of it
#: (docs/model.md Section 5).
TIMESTEP = 0.001
#: Control period (s): 1 kHz keeps the discretisation of the paper's continuous-time laws out of
#: the comparison.
CONTROL_DT = 0.001
#: Longest run accepted (s).
MAX_DURATION = 600.0
#: A run stops as a jackknife when |beta| or |phi| passes this (deg): just short of the
#: singularity at 90 deg, where the reduced model is undefined and the controller's g blows up.
JACKKNIFE_DEG = 85.0
#: Most physics steps in one run (duration / timestep): 600 s at 0.5 ms. Beyond it a run's
#: memory and time are not what anyone means to ask for.
MAX_PHYSICS_STEPS = 1_200_000
#: Most waypoints in a CSV path (a path, not a recorded trajectory at 1 kHz).
MAX_CSV_ROWS = 100_000
#: Speeds beyond this (m/s) are a numerical blow-up, not driving.
MAX_SPEED = 20.0
#: Longest clothoid path (m; its tables are made whole): what the longest run at the highest
#: speed could drive.
MAX_PATH_LENGTH = MAX_SPEED * MAX_DURATION
#: Wheel torque saturation (N m, the paper's Section 6.2): ``Params.torque_limit`` and the
#: controllers' default.
TORQUE_LIMIT = 15.0
#: Default controller of a run.
CONTROLLER = "ismc_sta"
#: Default disturbance Delta(t) (docs/model.md Section 8).
DISTURBANCE_MODEL = "paper"
#: Gain (1/m) of the path schedule's feedback to the path the tractor drove: an axle ``e``
#: beside it is steered ``atan(DRIVEN_PATH_GAIN e)`` back (docs/model.md Section 13).
DRIVEN_PATH_GAIN = 10.0
#: Slew rate (rad/s) of an actuated axle (``--eta path`` on the MuJoCo plant): its steering
#: target moves at most this fast. The path schedule's gain flips sign at an inflection, and an
#: unbounded actuator passed the flip on as a steering step of several degrees within a physics
#: step, a jolt that slipped the tractor's tyres (docs/model.md Section 13).
AXLE_SLEW_RATE = 1.0

#: Exit codes of every command: done; bad input (one message, nothing written); the run
#: diverged, jackknifed or its user code failed (what was computed is kept); interrupted.
EXIT_OK, EXIT_BAD_INPUT, EXIT_DIVERGED, EXIT_INTERRUPTED = 0, 2, 3, 130
#: A bug of ours (sysexits' EX_SOFTWARE): one line naming the file its traceback went to.
EXIT_BUG = 70
#: A run's wall-clock time limit (s): ends a run whose user code hangs (exit code 3). The
#: longest run the caps allow takes minutes, so the default never stops a working run.
TIME_LIMIT_S = 3600.0

#: The video's cameras (``--camera``): one that follows the tractor, one over the whole run.
CAMERAS = ("follow", "overview")

#: The along-track loop's gain on a planned path (1/s, ``Scenario.along_track_gain``): an
#: along-track error decays with a time constant of 1/3 s, half as fast as the speed loop
#: (ISMC-STA lambda = 6 1/s), so the loops do not fight; the run ends where its path does
#: (compare ``--along-track-gain 0`` on ``--world loading_bay --traj plan --reverse``).
DOCKING_GAIN = 3.0
