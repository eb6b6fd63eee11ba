#!/usr/bin/env python
"""evoik_pin's retargeting on every example-robot-data humanoid with a CMU preset (G1, Talos, Romeo, iCub): the
bundled clips, each judged by ``judge_retarget.py`` as ``bench_retarget.py`` judges G1 and Talos (no pink here).

    python scripts/retarget_every_humanoid.py [ROBOT ...] [--clips walk jump]"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_retarget as br  # noqa: E402

from evoik_pin.motion import ground_height  # noqa: E402

#: The humanoids beyond bench_retarget's two: URDF and SRDF below example-robot-data's robots/.
br.ROBOTS.update({"romeo": ("romeo_description/urdf/romeo.urdf", "romeo_description/srdf/romeo.srdf"),
                  "icub": ("icub_description/robots/icub.urdf", "icub_description/srdf/icub.srdf")})


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("robots", nargs="*", default=list(br.ROBOTS))
    ap.add_argument("--clips", nargs="+", default=br.list_clips())
    args = ap.parse_args()
    print(br.HEADER)
    print("|" + "---|" * (br.HEADER.count("|") - 1))
    for robot in args.robots:
        for clip in args.clips:
            case = br.prepare(clip, robot)
            report: dict = {}
            configurations, _ = br.retarget_evoik(robot, case["motion"], case["scale"], report)
            verdict = br.judge(robot, case, configurations, ground=ground_height(case["motion"]))
            print(br.row(clip, robot, "evoik_pin", verdict, report["steady_fps"], 1e3 * report["first_frame_s"]),
                  flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
