"""The CMU motion-capture clips shipped with evoik_pin (``motions/cmu/*.bvh``; credits in ``motions/README.md``).

Each clip is one CMU trial at 30 fps (run and jump whole, 1.4-4.0 s; walk its first second; dance and getup 0.5 s
cut from theirs), kept as a BVH file with CMU's hierarchy, so that examples and tests can retarget a real human
motion without a download. Found next to the installed package (``evoik_pin/motions``, pyproject's
``force-include``) or at the top of a source checkout.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import MotionError
from ..robot.frames import closest_names
from .bvh import load_bvh
from .motion import Motion

__all__ = ["CLIPS", "clip_path", "list_clips", "load_clip", "motions_dir"]

#: Bundled clips: name -> (file below motions/, what it shows and its CMU subject_trial).
CLIPS: dict[str, tuple[str, str]] = {
    "walk": ("cmu/walk.bvh", "walk forward, 1.0 s: right stance, then left stance (CMU 07_01)"),
    "run": ("cmu/run.bvh", "run, 1.43 s (the whole trial): four stances from the right foot's, a flight between "
                           "each (CMU 02_03)"),
    "jump": ("cmu/jump.bvh", "jump on the spot, 4.0 s (the whole trial): crouch, push-off, flight, landing in a "
                             "crouch, standing up, balancing (CMU 02_04)"),
    "dance": ("cmu/dance.bvh", "modern dance, 0.5 s: rising from a bend, arms sweeping (CMU 05_04)"),
    "getup": ("cmu/getup.bvh", "getting up from the ground, 0.5 s: squat to standing (CMU 140_03)"),
}


def motions_dir() -> Path:
    """Directory holding the bundled clips: ``evoik_pin/motions`` in an installed wheel, ``motions/`` at the top
    of a source checkout (``src/evoik_pin`` two levels below)."""
    package = Path(__file__).resolve().parents[1]  # evoik_pin/ (this file is evoik_pin/motion/clips.py)
    for candidate in (package / "motions", package.parents[1] / "motions"):
        if (candidate / "README.md").is_file() and (candidate / "cmu").is_dir():
            return candidate
    raise MotionError(f"bundled motions not found next to {package} (looked for motions/README.md and motions/cmu)")


def list_clips(describe: bool = False) -> list[str] | dict[str, str]:
    """Names accepted by :func:`clip_path`; ``describe=True``: a dict of those names to what each clip shows."""
    return {k: what for k, (_, what) in CLIPS.items()} if describe else list(CLIPS)


def clip_path(name: str) -> Path:
    """Path of the bundled BVH clip ``name`` (one of :func:`list_clips`)."""
    if name not in CLIPS:
        close = closest_names(str(name), list(CLIPS))
        raise MotionError(f"no bundled clip {name!r}; accepted: {list(CLIPS)}" + (f" (closest: {close})"
                                                                                   if close else ""))
    return motions_dir() / CLIPS[name][0]


def load_clip(name: str) -> Motion:
    """The bundled clip ``name`` as a :class:`Motion` (m, z up, 30 fps): ``load_bvh(clip_path(name))``."""
    return load_bvh(clip_path(name))
