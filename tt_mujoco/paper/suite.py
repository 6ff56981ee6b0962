"""The suite's runs: the table cells, the isolation variants, the two studies."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from tt_mujoco.paper import robustness
from tt_mujoco.sim import Scenario

#: Seed of every run (measurement noise); fixed so that the report is reproducible.
SUITE_SEED = 0


PLANTS = ("reduced", "mujoco")


PLANT_LABEL = {"reduced": "reduced", "mujoco": "MuJoCo"}


#: A cell is flagged when ours / paper is outside [1/FACTOR, FACTOR].
FACTOR = 2.0


#: Speeds below this (m/s) are left out of the curvature split (it divides by v).
V_MIN = 0.1


#: Distance (m) the trailer axle must be past a curvature change (or the start) for its
#: off-tracking to count as steady: the articulation settles over L0 / (1 - eta) = 0.36 m
#: (same-path) to 0.4 m (plain trailer) of travel, so 2 m leaves < 1 % of the transient.
SETTLE_DISTANCE = 2.0


#: Points kept per run for the figures.
SERIES_POINTS = 600


DEFAULT_OUT = Path("renders") / "paper"


COMMAND = "python -m tt_mujoco.paper"


# --- the paper's tables (docs/model.md Section 10; paper Tables 1-5)
# -----------------------------------
#: Scenario of each table row, without the plant. Tables 1-3 on the cycloid (Section 6.1-6.2),
#: Tables 4-5 on the S-curve and the circle (Section 6.3). Gain set "paper_6_1" (Section 6.1)
#: except Table 3's comparison set "paper_6_2"; the S-curve runs the paper's stated 10 s.
TABLE_RUNS: dict[str, dict] = {
    "cycloid_nominal": {"traj": "cycloid", "gains": "paper_6_1"},
    "cycloid_plus20": {"traj": "cycloid", "gains": "paper_6_1", "param_scale": 1.2},
    "cycloid_minus20": {"traj": "cycloid", "gains": "paper_6_1", "param_scale": 0.8},
    "cycloid_noise": {"traj": "cycloid", "gains": "paper_6_1", "noise_snr_db": 20.0},
    "cycloid_ismc_6_2": {"traj": "cycloid", "gains": "paper_6_2"},
    "cycloid_pid": {"traj": "cycloid", "controller": "pid", "gains": "paper_6_2"},
    "cycloid_fbl": {"traj": "cycloid", "controller": "fbl", "gains": "paper_6_2"},
    "s_curve_dynamic": {"traj": "s_curve", "gains": "paper_6_1", "duration": 10.0},
    "s_curve_static": {
        "traj": "s_curve",
        "target": "static",
        "gains": "paper_6_1",
        "duration": 10.0,
    },
    "circle_dynamic": {"traj": "circle", "gains": "paper_6_1"},
    "circle_static": {"traj": "circle", "target": "static", "gains": "paper_6_1"},
}


#: Table 3 with the baselines (docs/controllers.md), in Table 3's own case (cycloid, the paper's
#: disturbance, dynamic target): column name -> run (a key of TABLE_RUNS or BASELINE_RUNS).
BASELINE_RUNS: dict[str, dict] = {
    "cycloid_stanley": {"traj": "cycloid", "controller": "stanley"},
    "cycloid_lqr": {"traj": "cycloid", "controller": "lqr"},
    "cycloid_nmpc": {"traj": "cycloid", "controller": "nmpc"},
}
TABLE_3_CONTROLLERS = {
    "ISMC-STA": "cycloid_ismc_6_2",
    "PID": "cycloid_pid",
    "FBL": "cycloid_fbl",
    "Stanley": "cycloid_stanley",
    "LQR": "cycloid_lqr",
    "NMPC": "cycloid_nmpc",
}


TABLE_TITLES = {
    1: "Table 1. Tracking performance (RMSE) under parameter uncertainties (cycloid)",
    2: "Table 2. Tracking performance (RMSE) under measurement noise (cycloid)",
    3: "Table 3. Comparison of controllers (cycloid, dynamic target)",
    4: "Table 4. Dynamic vs static target, S-curve (RMSE)",
    5: "Table 5. Dynamic vs static target, unit circle (RMSE)",
}


QUANTITY = {
    "rmse_v": "e_v RMSE (m/s)",
    "rmse_omega": "e_omega RMSE (rad/s)",
    "rmse_lateral": "lateral deviation RMSE (m)",
    "max_abs_v": "max abs e_v (m/s)",
    "max_abs_omega": "max abs e_omega (rad/s)",
    "rmse_position": "position error RMSE (m)",
    "max_position": "max position error (m)",
}


@dataclass(frozen=True)
class Cell:
    """One number of the paper's Tables 1-5 and the run that reproduces it."""

    table: int
    case: str
    metric: str
    paper: float
    run: str  # a key of TABLE_RUNS

    @property
    def quantity(self) -> str:
        return QUANTITY[self.metric]


def _cells() -> tuple[Cell, ...]:
    out = []
    t1 = {"rmse_v": (0.0147, 0.0157, 0.0146), "rmse_omega": (0.0224, 0.0284, 0.0216)}
    t1["rmse_lateral"] = (0.0368, 0.0352, 0.0397)
    for i, (case, run) in enumerate(
        (("Nominal", "cycloid_nominal"), ("+20 %", "cycloid_plus20"), ("-20 %", "cycloid_minus20"))
    ):
        out += [Cell(1, case, m, vals[i], run) for m, vals in t1.items()]
    t2 = {"rmse_v": (0.0147, 0.0165), "rmse_omega": (0.0224, 0.0269)}
    t2["rmse_lateral"] = (0.0368, 0.0484)
    for i, (case, run) in enumerate(
        (("Without noise", "cycloid_nominal"), ("20 dB Gaussian noise", "cycloid_noise"))
    ):
        out += [Cell(2, case, m, vals[i], run) for m, vals in t2.items()]
    t3 = {
        ("ISMC-STA", "cycloid_ismc_6_2"): (0.0147, 0.0224, 0.0971, 0.0659),
        ("PID", "cycloid_pid"): (0.3273, 0.2544, 0.6669, 0.5585),
        ("FBL", "cycloid_fbl"): (0.5247, 0.2699, 0.6172, 0.5155),
    }
    for (case, run), vals in t3.items():
        metrics = ("rmse_v", "rmse_omega", "max_abs_v", "max_abs_omega")
        out += [Cell(3, case, m, v, run) for m, v in zip(metrics, vals, strict=True)]
    t45 = {
        (4, "Dynamic", "s_curve_dynamic"): (0.0091, 0.0137, 0.0514, 0.0174),
        (4, "Static", "s_curve_static"): (0.0261, 0.0131, 0.0969, 0.0488),
        (5, "Dynamic", "circle_dynamic"): (0.0111, 0.0131, 0.0223, 0.0174),
        (5, "Static", "circle_static"): (0.0115, 0.0131, 0.0151, 0.0174),
    }
    for (table, case, run), vals in t45.items():
        metrics = ("rmse_position", "rmse_v", "rmse_omega", "max_position")
        out += [Cell(table, case, m, v, run) for m, v in zip(metrics, vals, strict=True)]
    return tuple(out)


#: Every number of the paper's Tables 1-5 (43 cells).
CELLS = _cells()


#: Variants used by the isolation runs (key suffix "~name").
VARIANTS = {
    "gains_6_2": {"gains": "paper_6_2"},
    "mu3": {"friction": 3.0},
    "nodist": {"disturbance": "none"},
    "static_target": {"target": "static"},
}


# (table run, variant, plants): the isolation runs the causes below read.
_ISOLATION = (
    *((b, "gains_6_2", PLANTS) for b in ("cycloid_nominal", "cycloid_plus20", "cycloid_minus20")),
    *((b, "gains_6_2", PLANTS) for b in ("cycloid_noise", "s_curve_dynamic", "s_curve_static")),
    *((b, "gains_6_2", PLANTS) for b in ("circle_dynamic", "circle_static")),
    *((b, "mu3", ("mujoco",)) for b in TABLE_RUNS if b.startswith("cycloid")),
    *((b, "nodist", PLANTS) for b in ("cycloid_nominal", "circle_dynamic", "s_curve_static")),
    *((b, "static_target", PLANTS) for b in ("cycloid_pid", "cycloid_fbl")),
)


#: FBL with a stiff yaw loop: e_v ~ Delta1 / k_v ~ 0.5 m/s while e_omega stays small, the
#: situation in which eq. (39)'s static mismatch term matters.
STIFF_YAW_GAINS = {"k_v": 8.0, "k_omega": 50.0}


# --- steering and path-feedback studies --------------------------------------------------------
STUDY_PATHS = ("cycloid", "s_curve", "circle")


#: Steering designs of the study (the study runs without the paper's disturbance: off-tracking is
#: geometry, and reversing with eta = 3 the matched disturbance torques alone exceed 15 N m).
STEERING_VARIANTS: dict[str, dict] = {
    "plain (eta = 0)": {"eta": 0.0},
    "paper eta = 3, forward": {"eta": "paper"},
    # passive: the hitch left to itself, which eta = 3 holds reversing (no cascade)
    "paper eta = 3, reverse": {"eta": "paper", "reverse": True, "hitch_feedback": None},
    "eta = -3": {"eta": -3.0},
    "half-difference gain (-0.125)": {"eta": -0.125},
    "same_path (-1/7)": {"eta": "same_path"},
    "scheduled eta(kappa)": {"eta": "same_path", "eta_schedule": True},
    # each trailer's gain along the path from its geometry (docs/model.md Section 13)
    "path schedule eta(s)": {"eta": "same_path", "eta_schedule": "path"},
}


STEERING_BASE = {"controller": "ismc_sta", "gains": "paper_6_1", "disturbance": "none"}


#: Extra steering runs: (path, variant, overrides, plants, label).
STEERING_EXTRA = (
    ("circle", "paper eta = 3, reverse", {"disturbance": "matched"}, PLANTS, "with disturbance"),
    (
        "circle",
        "paper eta = 3, reverse",
        {"disturbance": "matched", "disturbance_limit": "none"},
        PLANTS,
        "with unbounded disturbance",
    ),
    ("cycloid", "eta = -3", {"friction": 3.0}, ("mujoco",), "friction 3"),
    ("s_curve", "eta = -3", {"friction": 3.0}, ("mujoco",), "friction 3"),
    ("s_curve", "paper eta = 3, reverse", {"friction": 3.0}, ("mujoco",), "friction 3"),
)


FEEDBACK_CASES: dict[str, dict] = {
    "cycloid": {"traj": "cycloid", "gains": "paper_6_1", "noise_snr_db": 20.0},
    "s_curve": {"traj": "s_curve", "gains": "paper_6_1", "noise_snr_db": 20.0},
    "circle": {"traj": "circle", "gains": "paper_6_1", "noise_snr_db": 20.0},
    "cycloid, no noise": {"traj": "cycloid", "gains": "paper_6_1"},
    "cycloid, gains 6.2": {"traj": "cycloid", "gains": "paper_6_2", "noise_snr_db": 20.0},
    "cycloid, paper start pose": {"traj": "cycloid", "gains": "paper_6_1", "start": "paper"},
}


@dataclass
class RunSpec:
    """One run of the suite: a unique key, the group it reports in, and its scenario."""

    key: str
    group: str
    scenario: Scenario
    keep_series: bool = False
    info: dict = field(default_factory=dict)


def _scenario(plant: str, **kw) -> Scenario:
    base = {"plant": plant, "seed": SUITE_SEED, "eta": "same_path"}
    return Scenario(**{**base, **kw})


def suite(quick: bool = False) -> list[RunSpec]:
    """The runs of the report.

    Parameters
    ----------
    quick : bool
        A reduced set for tests and smoke checks: Table 1's nominal run on both plants, one
        steering and one path-feedback run, each cut to 0.5 s. The report still lists every
        cell of Tables 1-5 (the missing ones as "not run").
    """
    specs: list[RunSpec] = []
    if quick:
        short = {"duration": 0.5}
        for plant in PLANTS:
            sc = _scenario(plant, **{**TABLE_RUNS["cycloid_nominal"], **short})
            specs.append(RunSpec(f"cycloid_nominal@{plant}", "table", sc, True))
        sc = _scenario("reduced", traj="circle", **STEERING_BASE, **short)
        specs.append(
            RunSpec(
                "steer:circle:same_path (-1/7)@reduced",
                "steering",
                sc,
                info={"path": "circle", "variant": "same_path (-1/7)", "label": ""},
            )
        )
        sc = _scenario("reduced", **FEEDBACK_CASES["circle"], path_feedback={}, **short)
        specs.append(
            RunSpec(
                "fb:circle:on@reduced", "feedback", sc, True, {"case": "circle", "feedback": "on"}
            )
        )
        return specs

    for base, kw in TABLE_RUNS.items():
        for plant in PLANTS:
            specs.append(RunSpec(f"{base}@{plant}", "table", _scenario(plant, **kw), True))
    for base, kw in BASELINE_RUNS.items():
        for plant in PLANTS:
            specs.append(RunSpec(f"{base}@{plant}", "baselines", _scenario(plant, **kw)))
    for path in robustness.PATHS:
        for case, fields in robustness.cases(path).items():
            for name, controller in robustness.CONTROLLERS.items():
                sc = _scenario("mujoco", traj=path, **fields, **controller)
                info = {"path": path, "case": case, "controller": name}
                key = robustness.run_key(path, case, name)
                specs.append(RunSpec(key, "robustness", sc, info=info))
    for base, variant, plants in _ISOLATION:
        for plant in plants:
            kw = {**TABLE_RUNS[base], **VARIANTS[variant]}
            specs.append(RunSpec(f"{base}~{variant}@{plant}", "isolation", _scenario(plant, **kw)))
    for traj in ("s_curve", "circle"):
        for target in ("dynamic", "static"):
            for plant in PLANTS:
                kw = {"traj": traj, "target": target, "controller": "fbl"}
                kw["gains"] = dict(STIFF_YAW_GAINS)
                if traj == "s_curve":
                    kw["duration"] = 10.0
                key = f"stiff_yaw_fbl:{traj}_{target}@{plant}"
                specs.append(RunSpec(key, "isolation", _scenario(plant, **kw), True))
    for plant in PLANTS:
        kw = {"traj": "cycloid", "target": "static", "gains": "paper_6_1"}
        specs.append(RunSpec(f"cycloid_static@{plant}", "analysis", _scenario(plant, **kw), True))
    for traj in STUDY_PATHS:
        for name, kw in STEERING_VARIANTS.items():
            for plant in PLANTS:
                sc = _scenario(plant, traj=traj, **STEERING_BASE, **kw)
                info = {"path": traj, "variant": name, "label": ""}
                specs.append(RunSpec(f"steer:{traj}:{name}@{plant}", "steering", sc, info=info))
    for traj, name, over, plants, label in STEERING_EXTRA:
        for plant in plants:
            kw = {**STEERING_BASE, **STEERING_VARIANTS[name], **over}
            info = {"path": traj, "variant": name, "label": label}
            key = f"steer:{traj}:{name}~{label}@{plant}"
            specs.append(RunSpec(key, "steering", _scenario(plant, traj=traj, **kw), info=info))
    for case, kw in FEEDBACK_CASES.items():
        for state in ("off", "on"):
            for plant in PLANTS:
                extra = {"path_feedback": {}} if state == "on" else {}
                sc = _scenario(plant, **kw, **extra)
                info = {"case": case, "feedback": state}
                specs.append(RunSpec(f"fb:{case}:{state}@{plant}", "feedback", sc, True, info))
    return specs
