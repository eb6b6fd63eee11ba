"""Motion: keypoint arrays checked when made, read-only after, and the helpers a retargeter reads."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evoik_pin.errors import EvoikError, MotionError
from evoik_pin.motion import Motion


def standing(n=5, fps=30.0):
    """A three-keypoint figure: ankle at z 0.1, hip at 0.9, head at 1.6 m, walking along x at 1 m/s."""
    t = np.arange(n) / fps
    base = np.array([[0.0, 0.0, 0.1], [0.0, 0.0, 0.9], [0.0, 0.0, 1.6]])
    p = np.repeat(base[None], n, axis=0)
    p[:, :, 0] += t[:, None]
    return Motion(p, ["ankle", "hip", "head"], fps)


def test_fields_and_derived_quantities():
    m = standing(n=31, fps=30.0)
    assert m.positions.shape == (31, 3, 3)
    assert m.names == ("ankle", "hip", "head")
    assert m.fps == 30.0 and m.frames == len(m) == 31
    assert m.duration == pytest.approx(1.0)
    np.testing.assert_allclose(m.times, np.arange(31) / 30.0)
    assert m.height() == pytest.approx(1.5)
    assert m.index("hip") == 1
    np.testing.assert_allclose(m.trajectory("head")[:, 2], 1.6)
    np.testing.assert_allclose(m.trajectory("head")[:, 0], np.arange(31) / 30.0)


def test_read_only():
    m = standing()
    with pytest.raises(ValueError):
        m.positions[0, 0, 0] = 1.0
    with pytest.raises(AttributeError):
        m.fps = 60.0


def test_pickle_and_deepcopy_round_trip():
    import copy
    import pickle

    m = standing()
    for twin in (pickle.loads(pickle.dumps(m)), copy.deepcopy(m)):
        np.testing.assert_array_equal(twin.positions, m.positions)
        assert twin.names == m.names and twin.fps == m.fps
        with pytest.raises(AttributeError):
            twin.fps = 1.0


def test_input_is_copied():
    p = np.zeros((2, 1, 3))
    m = Motion(p, ["a"], 10)
    p[0, 0, 0] = 5.0
    assert m.positions[0, 0, 0] == 0.0


@pytest.mark.parametrize("fps", [0, -30, float("nan"), float("inf"), "fast", None])
def test_bad_fps(fps):
    with pytest.raises(MotionError, match="fps"):
        Motion(np.zeros((2, 1, 3)), ["a"], fps)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_keypoints_name_the_frame_and_keypoint(bad):
    p = np.zeros((4, 2, 3))
    p[2, 1, 0] = bad
    with pytest.raises(MotionError, match="frame 2, keypoint 1"):
        Motion(p, ["a", "b"], 30)


@pytest.mark.parametrize("shape", [(0, 2, 3), (3, 0, 3)])
def test_empty_motion(shape):
    with pytest.raises(MotionError, match="empty"):
        Motion(np.zeros(shape), ["a", "b"][: shape[1]], 30)


@pytest.mark.parametrize("shape", [(3, 2), (3, 2, 2), (3, 2, 3, 1)])
def test_wrong_shape(shape):
    with pytest.raises(MotionError, match=r"\(N frames, K keypoints, 3\)"):
        Motion(np.zeros(shape), ["a", "b"], 30)


def test_names_checked():
    p = np.zeros((2, 2, 3))
    with pytest.raises(MotionError, match="unique"):
        Motion(p, ["a", "a"], 30)
    with pytest.raises(MotionError, match="2 non-empty strings"):
        Motion(p, ["a"], 30)
    with pytest.raises(MotionError, match="2 non-empty strings"):
        Motion(p, ["a", ""], 30)
    with pytest.raises(MotionError, match="not one string"):
        Motion(p, "ab", 30)


def test_non_numeric_positions():
    with pytest.raises(MotionError, match="numbers"):
        Motion(np.array([[["a", "b", "c"]]]), ["k"], 30)


def test_error_classes():
    assert issubclass(MotionError, EvoikError) and issubclass(MotionError, ValueError)


def test_unknown_keypoint_suggests_the_closest():
    m = standing()
    with pytest.raises(MotionError, match="closest: \\['head'\\]"):
        m.index("haed")
    with pytest.raises(MotionError, match="no keypoint"):
        m.trajectory("elbow")


def test_slice():
    m = standing(n=10)
    s = m.slice(2, 5)
    assert s.frames == 3 and s.fps == m.fps and s.names == m.names
    np.testing.assert_array_equal(s.positions, m.positions[2:5])
    np.testing.assert_array_equal(m.slice(-3).positions, m.positions[-3:])
    with pytest.raises(MotionError, match="no frame"):
        m.slice(5, 5)
    with pytest.raises(MotionError, match="no frame"):
        m.slice(20)


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(2, 40),
    fps=st.floats(5.0, 240.0),
    new_fps=st.floats(5.0, 240.0),
    velocity=st.tuples(*[st.floats(-3.0, 3.0)] * 3),
)
def test_resampling_is_exact_on_linear_motion(n, fps, new_fps, velocity):
    """Linear interpolation reproduces a constant-velocity trajectory at any new rate, over the same span."""
    v = np.array(velocity)
    t = np.arange(n) / fps
    m = Motion(np.array([0.1, -0.2, 0.9]) + t[:, None, None] * v, ["p"], fps)
    r = m.resampled(new_fps)
    assert r.fps == new_fps
    assert r.duration <= m.duration + 1e-9
    assert m.duration - r.duration < 1.0 / new_fps + 1e-9
    np.testing.assert_allclose(r.positions[:, 0], np.array([0.1, -0.2, 0.9]) + r.times[:, None] * v, atol=1e-9)


def test_resampling_keeps_the_frames_at_the_same_rate():
    m = standing(n=7)
    np.testing.assert_allclose(m.resampled(m.fps).positions, m.positions)
    with pytest.raises(MotionError, match="fps"):
        m.resampled(0)


def test_height_is_the_median_vertical_extent():
    p = np.zeros((3, 2, 3))
    p[:, 1, 2] = [1.0, 1.7, 1.8]  # one crouched frame does not move the median
    assert Motion(p, ["foot", "head"], 30).height() == pytest.approx(1.7)
