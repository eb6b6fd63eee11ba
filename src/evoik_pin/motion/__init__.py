"""Motions as data: keypoint trajectories (:class:`Motion`), BVH files (:func:`load_bvh`), the bundled CMU clips
(:func:`clip_path`, :func:`list_clips`), foot contacts (:func:`detect_contacts`) and robot-to-motion mappings
(:func:`resolve_mapping`, presets for SMPL and CMU skeletons onto G1, Talos, Romeo and iCub).

* :mod:`.motion`: the :class:`Motion` class (positions (N, K, 3) m z up, names, fps) and its helpers;
* :mod:`.bvh`: BVH parser and vectorized forward kinematics; :mod:`.units`: length units and their inference;
* :mod:`.clips`: the bundled clips; :mod:`.contacts`: foot contacts; :mod:`.mapping`: mapping presets and checks;
* :mod:`.retarget`: :func:`retarget`, a motion onto a humanoid, returning a :class:`Clip` (:mod:`.clip`) with its
  quality report (:mod:`.retarget_report`).
"""

from .bvh import load_bvh
from .clip import Clip
from .clips import clip_path, list_clips, load_clip
from .contacts import detect_contacts, ground_height
from .mapping import limb_pairs, mapping_preset, resolve_mapping
from .motion import Motion
from .retarget import retarget

__all__ = [
    "Clip",
    "Motion",
    "clip_path",
    "detect_contacts",
    "ground_height",
    "limb_pairs",
    "list_clips",
    "load_bvh",
    "load_clip",
    "mapping_preset",
    "resolve_mapping",
    "retarget",
]
