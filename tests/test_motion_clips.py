"""The bundled CMU clips: found, loaded as plausible humans at 30 fps, facing +x with the left side on +y, and with
the contacts their motion has (alternating on the walk, a flight phase on the run and the jump)."""

import numpy as np
import pytest

from evoik_pin.errors import MotionError
from evoik_pin.motion import clip_path, detect_contacts, list_clips, load_clip
from evoik_pin.motion.clips import CLIPS, motions_dir


@pytest.fixture(scope="module")
def clips():
    return {name: load_clip(name) for name in list_clips()}


def test_clip_files_are_bundled_and_small():
    assert list_clips() == list(CLIPS) and len(CLIPS) >= 5
    assert set(list_clips(describe=True)) == set(CLIPS)
    assert (motions_dir() / "README.md").read_text().count("NSF EIA-0196217") == 1
    for name in list_clips():
        path = clip_path(name)
        assert path.is_file() and path.suffix == ".bvh"
        assert path.stat().st_size < 150_000


def test_unknown_clip_names_the_closest():
    with pytest.raises(MotionError, match="closest: \\['walk'\\]"):
        clip_path("wlak")


def test_clips_are_plausible_humans(clips):
    for name, m in clips.items():
        assert m.fps == 30.0, name
        assert 15 <= m.frames <= 300, name
        leg = np.linalg.norm(m.trajectory("LeftUpLeg") - m.trajectory("LeftLeg"), axis=1) + np.linalg.norm(
            m.trajectory("LeftLeg") - m.trajectory("LeftFoot"), axis=1)
        assert 0.7 < leg.mean() < 1.0, name  # thigh + shank of an adult, m
        # CMU's skeleton ends at the head joint's end site, below the top of the skull: its keypoint extent reads
        # about 1.4 m for subjects whose legs say 1.6-1.7 m tall
        if name in ("walk", "run", "dance"):  # upright clips
            assert 1.3 < m.height() < 2.0, name


def test_walk_faces_x_with_the_left_side_on_y(clips):
    m = clips["walk"]
    velocity = (m.trajectory("Hips")[-1] - m.trajectory("Hips")[0]) / m.duration
    assert velocity[0] > 1.0 and abs(velocity[1]) < 0.2  # walking forward at 1.2-1.5 m/s
    assert (m.trajectory("LeftUpLeg")[:, 1] > m.trajectory("RightUpLeg")[:, 1]).all()  # nothing mirrored
    assert 0.8 < m.trajectory("Hips")[:, 2].mean() < 1.05


def _single_support_runs(left, right):
    """``[(foot letter, frames)]``: the runs of frames where exactly one foot is in contact, in order."""
    runs = []
    for letter in np.where(left & ~right, "L", np.where(right & ~left, "R", "")):
        if letter and runs and runs[-1][0] == letter and runs[-1][2]:
            runs[-1][1] += 1
        elif letter:
            runs.append([letter, 1, True])
        elif runs:
            runs[-1][2] = False  # a gap (double support or none) ends the run
    return [(foot, n) for foot, n, _ in runs]


def test_walk_contacts_alternate(clips):
    c = detect_contacts(clips["walk"])
    left, right = c["LeftFoot"], c["RightFoot"]
    assert right[0] and not left[0]  # starts on the right foot, the left swinging
    assert left[-1] and not right[-1]  # ends on the left foot
    first_left = np.argmax(left)
    assert not right[first_left:].any() and right[:first_left - 2].all()


def test_run_has_a_flight_phase(clips):
    c = detect_contacts(clips["run"])
    airborne = ~c["LeftFoot"] & ~c["RightFoot"]
    assert airborne.sum() >= 3 and c["LeftFoot"].any() and c["RightFoot"].any()
    stances = _single_support_runs(c["LeftFoot"], c["RightFoot"])
    assert "".join(foot for foot, _ in stances) == "RLRL"  # the whole trial: four stances, alternating


def test_jump_takes_off_and_lands(clips):
    m = clips["jump"]
    c = detect_contacts(m)
    apex = np.argmax(m.trajectory("Hips")[:, 2])
    assert not c["LeftFoot"][apex] and not c["RightFoot"][apex]
    assert c["LeftFoot"][0] and c["RightFoot"][0] and c["LeftFoot"][-1] and c["RightFoot"][-1]
    hips = m.trajectory("Hips")[:, 2]
    landing = apex + np.argmin(hips[apex:])
    assert hips[apex] - hips[landing] > 0.4  # a real jump, landed in a crouch
    assert hips[-1] - hips[landing] > 0.15  # and stood up again: the whole trial


def test_getup_rises_and_dance_moves(clips):
    hips = clips["getup"].trajectory("Hips")[:, 2]
    assert hips[0] < 0.6 and hips[-1] > 0.8 and (np.diff(hips) > 0).all()  # squat to standing
    d = clips["dance"]
    assert np.linalg.norm(d.trajectory("LeftHand")[-1] - d.trajectory("LeftHand")[0]) > 0.2
