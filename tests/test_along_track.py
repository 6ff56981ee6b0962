"""The along-track loop (Scenario.along_track_gain): the speed target corrected toward where the
profile puts the tractor on its path, so that noise on the measured speed no longer carries the
tractor ahead of or behind its reference."""

import pytest

from tt_mujoco.sim import Scenario, build, simulate


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_loop_holds_the_tractor_at_its_place_along_the_path(seed):
    """S-curve, reduced plant, 20 dB noise, no disturbance. Measured along-track rms: 9.9,
    18.1, 13.9 mm without the loop; 2.0, 2.2, 2.4 mm with k_s = 3 1/s (MuJoCo: 9.8-17.8 and
    2.0-2.5 mm)."""

    def along(gain):
        scenario = Scenario(
            traj="s_curve",
            seed=seed,
            noise_snr_db=20.0,
            plant="reduced",
            along_track_gain=gain,
            disturbance="none",
        )
        return simulate(scenario).metrics["along_track_rms"]

    assert along(0.0) > 0.009
    assert along(3.0) < 0.003


def test_the_loop_is_off_by_default_and_on_for_a_planned_path():
    assert build(Scenario()).along_track_gain == 0.0
    planned = Scenario(world="loading_bay", traj="plan", reverse=True, plant="reduced")
    assert build(planned).along_track_gain == 3.0
    assert build(Scenario(along_track_gain=0.5)).along_track_gain == 0.5
