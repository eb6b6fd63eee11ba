"""load_bvh: hand-written BVH files whose joint positions are known, any channel order, axes, units and every
error a malformed file can raise."""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from evoik_pin.errors import BvhError, MotionError
from evoik_pin.motion import load_bvh
from evoik_pin.motion.bvh import Y_UP_TO_Z_UP, parse_bvh
from evoik_pin.motion.units import UNITS, infer_unit, unit_scale

ORDERS = ["".join(p) for p in itertools.permutations("XYZ")]


def chain_bvh(frames, root_order="ZYX", knee_order="XYZ", offsets=((0, 0, 0), (0, -40, 0), (0, -45, 0)),
              frame_time=".0333333", root_position=True):
    """A Hips -> Knee -> End Site chain; ``frames`` rows are (x, y, z, 3 root angles, 3 knee angles) in the
    channel orders given (deg)."""
    (o0, o1, o2) = (" ".join(str(v) for v in o) for o in offsets)
    pos = "Xposition Yposition Zposition " if root_position else ""
    count = 6 if root_position else 3
    rot = lambda order: " ".join(f"{a}rotation" for a in order)  # noqa: E731
    lines = [
        "HIERARCHY", "ROOT Hips", "{", f"  OFFSET {o0}", f"  CHANNELS {count} {pos}{rot(root_order)}",
        "  JOINT Knee", "  {", f"    OFFSET {o1}", f"    CHANNELS 3 {rot(knee_order)}",
        "    End Site", "    {", f"      OFFSET {o2}", "    }", "  }", "}",
        "MOTION", f"Frames: {len(frames)}", f"Frame Time: {frame_time}",
    ]
    lines += [" ".join(repr(float(v)) for v in row) for row in frames]  # full precision: exact references
    return "\n".join(lines) + "\n"


def write(tmp_path, text, name="clip.bvh"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_hand_computed_positions(tmp_path):
    """Root at (10, 90, 0) cm turned 90 deg about z, knee turned 90 deg about x: worked out by hand."""
    rows = [[0, 90, 0, 0, 0, 0, 0, 0, 0], [10, 90, 0, 90, 0, 0, 90, 0, 0]]
    m = load_bvh(write(tmp_path, chain_bvh(rows, root_order="ZYX", knee_order="XYZ")), unit="cm", up="z")
    assert m.names == ("Hips", "Knee", "Knee_end")
    assert m.fps == 30.0
    # frame 0: straight down from (0, 90, 0)
    np.testing.assert_allclose(m.positions[0], [[0, 0.9, 0], [0, 0.5, 0], [0, 0.05, 0]], atol=1e-12)
    # frame 1: Rz(90) takes the knee offset (0, -40, 0) to (40, 0, 0); Rz(90) Rx(90) takes (0, -45, 0) to (0, 0, -45)
    np.testing.assert_allclose(m.positions[1], [[0.1, 0.9, 0], [0.5, 0.9, 0], [0.5, 0.9, -0.45]], atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    root_order=st.sampled_from(ORDERS),
    knee_order=st.sampled_from(ORDERS),
    angles=st.lists(st.floats(-180, 180), min_size=6, max_size=6),
    root=st.lists(st.floats(-100, 100), min_size=3, max_size=3),
)
def test_any_channel_order_matches_a_rotation_matrix_reference(tmp_path_factory, root_order, knee_order, angles,
                                                               root):
    """BVH Euler channels are intrinsic rotations in the listed order: scipy's upper-case sequences."""
    offsets = ((0, 0, 0), (3.0, -40.0, 1.0), (0.5, -45.0, 2.0))
    text = chain_bvh([root + angles], root_order, knee_order, offsets)
    m = load_bvh(write(tmp_path_factory.mktemp("bvh"), text), unit="cm", up="z")
    R0 = Rotation.from_euler(root_order, angles[:3], degrees=True).as_matrix()
    R1 = R0 @ Rotation.from_euler(knee_order, angles[3:], degrees=True).as_matrix()
    hips = np.array(root)
    knee = hips + R0 @ np.array(offsets[1])
    end = knee + R1 @ np.array(offsets[2])
    np.testing.assert_allclose(m.positions[0], np.array([hips, knee, end]) / 100.0, atol=1e-9)


def test_channel_order_of_position_and_rotation_is_free(tmp_path):
    """Rotation channels before position channels, on a 6-channel root: the same pose."""
    text = chain_bvh([[5, 80, 2, 30, 0, 0, 0, 0, 0]], root_order="ZYX")
    swapped = text.replace("CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation",
                           "CHANNELS 6 Zrotation Yrotation Xrotation Xposition Yposition Zposition")
    swapped = swapped.replace("5.0 80.0 2.0 30.0 0.0 0.0", "30.0 0.0 0.0 5.0 80.0 2.0")
    a = load_bvh(write(tmp_path, text, "a.bvh"), unit="cm", up="z")
    b = load_bvh(write(tmp_path, swapped, "b.bvh"), unit="cm", up="z")
    np.testing.assert_allclose(a.positions, b.positions, atol=1e-12)


def test_position_channels_replace_the_offset(tmp_path):
    """LAFAN1's root holds its world position in its channels next to a rest OFFSET: the channels win."""
    text = chain_bvh([[1, 95, 3, 0, 0, 0, 0, 0, 0]], offsets=((-14, 90, -85), (0, -40, 0), (0, -45, 0)))
    m = load_bvh(write(tmp_path, text), unit="cm", up="z")
    np.testing.assert_allclose(m.positions[0, 0], [0.01, 0.95, 0.03])


def test_a_root_without_position_channels_sits_at_its_offset(tmp_path):
    text = chain_bvh([[0, 0, 0, 0, 0, 0]], offsets=((1, 95, 2), (0, -40, 0), (0, -45, 0)), root_position=False)
    m = load_bvh(write(tmp_path, text), unit="cm", up="z")
    np.testing.assert_allclose(m.positions[0, :, 1], [0.95, 0.55, 0.10])


def test_y_up_becomes_z_up_without_mirroring(tmp_path):
    assert np.linalg.det(Y_UP_TO_Z_UP) == pytest.approx(1.0)
    np.testing.assert_allclose(Y_UP_TO_Z_UP @ Y_UP_TO_Z_UP.T, np.eye(3))
    rows = [[7, 90, 3, 20, 10, -5, 30, 0, 0]]
    path = write(tmp_path, chain_bvh(rows))
    z_up = load_bvh(path, unit="cm", up="z").positions
    y_up = load_bvh(path, unit="cm").positions  # the default: a Y-up file
    np.testing.assert_allclose(y_up, z_up @ Y_UP_TO_Z_UP.T)
    # file axes (x, y, z) -> (z, x, y): height (file y) becomes z, the forward file z becomes x, left file x is y
    np.testing.assert_allclose(y_up[0, 0], [0.03, 0.07, 0.90])
    with pytest.raises(BvhError, match="up must be"):
        load_bvh(path, up="x")


@pytest.mark.parametrize(("size", "unit"), [(1.75, "m"), (172.0, "cm"), (1690.0, "mm"), (66.0, "inch"),
                                            (30.0, "cmu")])
def test_unit_inferred_from_the_skeleton_size(tmp_path, size, unit):
    legs = 0.55 * size
    text = chain_bvh([[0, legs, 0, 0, 0, 0, 180, 0, 0]], offsets=((0, 0, 0), (0, -legs, 0), (0, -size, 0)))
    assert infer_unit(size) == unit
    m = load_bvh(write(tmp_path, text))  # hips at legs height, knee on the floor, the end site (flipped) at size
    assert m.positions[0, :, 2].max() - m.positions[0, :, 2].min() == pytest.approx(size * UNITS[unit])


def test_unit_override(tmp_path):
    path = write(tmp_path, chain_bvh([[0, 90, 0, 0, 0, 0, 0, 0, 0]]))
    assert load_bvh(path, unit="m").positions[0, 0, 2] == pytest.approx(90.0)
    assert load_bvh(path, unit=0.5).positions[0, 0, 2] == pytest.approx(45.0)
    assert unit_scale("cmu") == pytest.approx(0.0254 / 0.45)
    for bad in ("furlong", 0, -1.0, float("nan"), "1m", None):
        with pytest.raises(BvhError, match="unit"):
            unit_scale(bad)


def test_fps_from_frame_time_and_resampling(tmp_path):
    rows = [[i, 90, 0, 0, 0, 0, 0, 0, 0] for i in range(13)]  # root moving 1 cm per frame
    path = write(tmp_path, chain_bvh(rows, frame_time=".0083333"))
    m = load_bvh(path, unit="cm")
    assert m.fps == 120.0  # 1 / .0083333 = 120.0005: the file's cut digits, read as 120 fps
    r = load_bvh(path, unit="cm", fps=30)
    assert r.fps == 30 and r.frames == 4
    np.testing.assert_allclose(r.trajectory("Hips")[:, 1], [0.0, 0.04, 0.08, 0.12], atol=1e-12)


def test_parse_keeps_the_hierarchy():
    sk = parse_bvh(chain_bvh([[0] * 9, [1] * 9]))
    assert sk.names == ("Hips", "Knee", "Knee_end")
    np.testing.assert_array_equal(sk.parents, [-1, 0, 1])
    assert sk.channels[2] == () and sk.values.shape == (2, 9) and sk.frame_time == pytest.approx(0.0333333)


GOOD = chain_bvh([[0, 90, 0, 0, 0, 0, 0, 0, 0], [0, 90, 0, 0, 0, 0, 0, 0, 0]])


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "empty BVH"),
        (GOOD.replace("HIERARCHY", "HIERARCHIE"), "must start with HIERARCHY"),
        (GOOD.split("MOTION")[0], "no MOTION"),
        (GOOD.replace("Frames: 2", "Frames: 3"), "Frames: 3 but the file has 2"),
        (GOOD.replace("Frames: 2", "Frames: two"), "whole number"),
        (GOOD.replace("Frames: 2", "Frames: 0").rsplit("\n", 3)[0], "Frames: 0"),
        (GOOD.replace("Frame Time: .0333333", "Frame Time: 0"), "Frame Time must be > 0"),
        (GOOD.replace("Frame Time: .0333333", "Frame Time: -1"), "Frame Time must be > 0"),
        (GOOD.replace("Frame Time: .0333333", "Frame Time: soon"), "'soon' is not a number"),
        (GOOD.replace("Frame Time: .0333333", "Frametime: 1"), "expected 'Frame Time:'"),
        (GOOD.rstrip("\n") + " 0\n", "line 20: 10 values; the hierarchy has 9 channels"),
        (GOOD.replace("0.0 90.0", "x 90.0", 1), "line 19: 'x' is not a number"),
        (GOOD.replace("0.0 90.0", "nan 90.0", 1), "line 19: a value is not a finite number"),
        (GOOD.replace("CHANNELS 3 Xrotation Yrotation Zrotation", "CHANNELS 3 Xrotation Yrotation Wrotation"),
         "line 9: CHANNELS 3 must list 3 different channels"),
        (GOOD.replace("CHANNELS 3 Xrotation Yrotation Zrotation", "CHANNELS 3 Xrotation Yrotation Xrotation"),
         "different channels"),
        (GOOD.replace("CHANNELS 3 Xrotation Yrotation Zrotation", "CHANNELS 4 Xrotation Yrotation Zrotation"),
         "line 9: CHANNELS 4 must list 4"),
        (GOOD.replace("CHANNELS 3 Xrotation Yrotation Zrotation", "CHANNELS 7 Xrotation Yrotation Zrotation"),
         "count from 1 to 6"),
        (GOOD.replace("OFFSET 0 -40 0", "OFFSET 0 -40 zero"), "line 8: 'zero' is not a number"),
        (GOOD.replace("  JOINT Knee", "  JOINT Hips"), "appears twice"),
        (GOOD.replace("    End Site", "    End Point"), "must be followed by 'Site'"),
        (GOOD.replace("}\nMOTION", "MOTION"), "still open"),
        (GOOD.replace("  JOINT Knee", "  BONE Knee"), "unexpected 'BONE'"),
    ],
)
def test_malformed_files_name_the_line(text, message):
    with pytest.raises(BvhError, match=message):
        parse_bvh(text, "clip.bvh")


def test_errors_name_the_file_and_are_motion_errors(tmp_path):
    assert issubclass(BvhError, MotionError)
    path = write(tmp_path, GOOD.replace("Frame Time: .0333333", "Frame Time: 0"), "broken.bvh")
    with pytest.raises(BvhError, match="broken.bvh: line 18"):
        load_bvh(path)
    with pytest.raises(BvhError, match="cannot read BVH file"):
        load_bvh(tmp_path / "missing.bvh")
