"""Reachability maps: which voxels of the workspace the tip reaches, in how many orientations, how dexterously
(:func:`reachability_map`; definitions and options: docs/SCALE.md)."""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .call_setup import _robot, _run, make_problem
from .errors import OptionError, OutputError
from .problem import Target, coerce_scene
from .robot import Robot, load_robot
from .solvers.batch.batch_results import BatchOutcome
from .solvers.batch.solve_many_call import batch_engine, check_backend
from .solvers.batch.threads import ProgressBar, check_call, gc_paused
from .solvers.options import check_int, check_positive

__all__ = ["ReachMap", "output_dir", "reachability_map", "so3_samples"]

#: Random configurations whose tip positions bound the workspace.
WORKSPACE_SAMPLES = 50_000
#: Most voxels a map may have (a smaller voxel over a large workspace would take days).
MAX_VOXELS = 2_000_000
#: Targets handed to the batch engine at a time.
DEFAULT_BATCH = 50_000


@dataclass
class ReachMap:
    """A reachability map (:func:`reachability_map`).

    Attributes:
        centers: (M, 3) voxel centres (m, base frame); every voxel of the padded workspace box (planar arms: one
            layer in the arm's plane).
        index: (M,) reachability index in [0, 1]. manipulability: (M,) best manipulability (0: not reached).
        voxel: edge (m). orientations: orientations asked per voxel (1 for position-only and planar arms).
        kind: "pose", "position" or "planar". seed: the seed of every random choice. robot, tip, base: names.
        shape: voxels along x, y, z; ``centers`` is that grid in C order (z fastest), so
            ``index.reshape(shape)[i, j, k]`` is voxel (x_i, y_j, z_k). time_s: wall time. settings: the rest.
    """

    centers: np.ndarray
    index: np.ndarray
    manipulability: np.ndarray
    voxel: float
    orientations: int
    kind: str
    seed: int
    robot: str
    tip: str
    base: str
    shape: tuple[int, int, int]
    time_s: float
    settings: dict = field(default_factory=dict)

    @property
    def reached(self) -> np.ndarray:
        """(M,) bool: voxels reached in at least one orientation."""
        return self.index > 0

    def save(self, out_dir, png: bool = True, html: bool = True, robot: Robot | None = None) -> dict[str, Path]:
        """Write ``<robot>_reach.npz`` and, unless turned off, ``<robot>_reach.png`` (slices) and
        ``<robot>_reach.html`` (meshcat point cloud of the reached voxels, with ``robot`` drawn when given).
        Returns the paths by kind ("npz", "png", "html")."""
        stem = output_dir(out_dir) / f"{self.robot}_reach"
        paths = {"npz": stem.with_suffix(".npz")}
        np.savez_compressed(paths["npz"], centers=self.centers, index=self.index, manipulability=self.manipulability,
                            voxel=self.voxel, orientations=self.orientations, kind=self.kind, seed=self.seed,
                            robot=self.robot, tip=self.tip, base=self.base, shape=np.array(self.shape),
                            time_s=self.time_s, settings=json.dumps(self.settings))
        if png:
            paths["png"] = self.save_png(stem.with_suffix(".png"))
        if html:
            paths["html"] = self.save_html(stem.with_suffix(".html"), robot)
        return paths

    @classmethod
    def load(cls, path) -> ReachMap:
        """A map :meth:`save` wrote."""
        with np.load(Path(path).expanduser()) as z:
            return cls(z["centers"], z["index"], z["manipulability"], float(z["voxel"]), int(z["orientations"]),
                       str(z["kind"]), int(z["seed"]), str(z["robot"]), str(z["tip"]), str(z["base"]),
                       tuple(int(v) for v in z["shape"]), float(z["time_s"]), json.loads(str(z["settings"])))

    def save_png(self, path) -> Path:
        """Slices of the index: horizontal layers (up to 8, evenly spread over the reached heights) and the
        vertical x-z slice nearest y = 0 (one image for a planar arm)."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        nx, ny, nz = self.shape
        grid = self.index.reshape(nx, ny, nz)
        xs, ys, zs = (np.unique(self.centers[:, k]) for k in range(3))
        h = self.voxel / 2
        ext_xy, ext_xz = [xs[0] - h, xs[-1] + h, ys[0] - h, ys[-1] + h], [xs[0] - h, xs[-1] + h, zs[0] - h, zs[-1] + h]
        layers = np.nonzero(grid.max(axis=(0, 1)) > 0)[0]
        if layers.size == 0:
            layers = np.array([nz // 2])
        layers = layers[np.unique(np.linspace(0, layers.size - 1, min(8, layers.size)).round().astype(int))]
        # (cut, extent, title, vertical axis): horizontal layers, then the vertical x-z slice nearest y = 0
        panels = [(grid[:, :, k], ext_xy, f"z = {zs[k]:.3f} m" if nz > 1 else "plane of the arm", "y (m)")
                  for k in layers]
        if nz > 1:
            k = int(np.abs(ys).argmin())
            panels.append((grid[:, k, :], ext_xz, f"y = {ys[k]:.3f} m", "z (m)"))
        cols = min(3, len(panels))
        rows = -(-len(panels) // cols)
        fig, axes = plt.subplots(rows, cols, figsize=(max(6.0, 4.2 * cols), 3.8 * rows + 0.6), squeeze=False,
                                 layout="constrained")  # no label overlaps its neighbour panel
        image = None
        for ax, (cut, extent, title, vertical) in zip(axes.ravel(), panels, strict=False):
            image = ax.imshow(cut.T, origin="lower", extent=extent, vmin=0, vmax=1, cmap="viridis")
            ax.set_title(title)
            ax.set_xlabel("x (m)")
            ax.set_ylabel(vertical)
            ax.set_aspect("equal")
        for ax in axes.ravel()[len(panels):]:
            ax.axis("off")
        what = "reached" if self.kind != "pose" else f"reachability index ({self.orientations} orientations)"
        fig.colorbar(image, ax=axes.ravel().tolist(), shrink=0.8, label=what)
        fig.suptitle(f"{self.robot}: {what}, voxel {self.voxel * 100:g} cm, {int(self.reached.sum())} of "
                     f"{self.index.size} voxels reached", fontsize=10)
        out = Path(path).expanduser()
        try:
            fig.savefig(out, dpi=90)
        except OSError as exc:
            raise OutputError(f"cannot write {str(out)!r}: {exc.strerror or exc}") from None
        finally:
            plt.close(fig)
        return out

    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) corners (3,) in m of the reached voxels' box (of every voxel when none is reached)."""
        centers = self.centers[self.reached] if self.reached.any() else self.centers
        return centers.min(axis=0) - self.voxel / 2, centers.max(axis=0) + self.voxel / 2

    def save_html(self, path, robot: Robot | None = None) -> Path:
        """A self-contained meshcat page: the reached voxels as a point cloud coloured by the index (viridis, 0
        to 1), and ``robot`` at its zero configuration (clipped into its bounds) when given. The camera frames the
        map (:meth:`box`), not the robot."""
        from .viz import Viewer

        robot = robot or load_robot(self.robot, tip=self.tip, base=self.base)
        reached = self.reached
        with Viewer(robot, skeleton=None) as viewer:
            viewer.show(np.clip(np.zeros(robot.n), robot.lower, robot.upper))
            if reached.any():
                viewer.show_points(self.centers[reached], self.index[reached], name="reach", size=0.4 * self.voxel)
            viewer.frame(np.array(self.box()))
            return viewer.save_html(path)


def output_dir(path) -> Path:
    """The directory ``path``, created if needed; an OutputError when it cannot be."""
    out = Path(path).expanduser()
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create the output directory {str(out)!r}: {exc.strerror or exc}") from None
    return out


def so3_samples(count: int) -> np.ndarray:
    """``count`` rotation matrices (count, 3, 3) spread evenly over SO(3): super-Fibonacci spirals (Alexa 2022),
    deterministic."""
    import pinocchio as pin

    phi, psi = np.sqrt(2.0), 1.533751168755204288118041
    s = np.arange(count) + 0.5
    r, R = np.sqrt(s / count), np.sqrt(1.0 - s / count)
    a, b = 2.0 * np.pi * s / phi, 2.0 * np.pi * s / psi
    return np.array([pin.Quaternion(R[k] * np.cos(b[k]), r[k] * np.sin(a[k]), r[k] * np.cos(a[k]),
                                    R[k] * np.sin(b[k])).normalized().toRotationMatrix() for k in range(count)])


def _grid(lo: np.ndarray, hi: np.ndarray, voxel: float, planar_z: float | None):
    """Voxel centres covering [lo, hi] (edges on multiples of ``voxel``); planar: one layer at ``planar_z``."""
    axes = []
    for k in range(3):
        if planar_z is not None and k == 2:
            axes.append(np.array([planar_z]))
            continue
        first, last = np.floor(lo[k] / voxel), np.ceil(hi[k] / voxel)
        axes.append((np.arange(first, last) + 0.5) * voxel)
    shape = tuple(a.size for a in axes)
    if np.prod(shape, dtype=float) > MAX_VOXELS:
        raise OptionError(f"voxel {voxel:g} m cuts the workspace ({np.round(hi - lo, 3).tolist()} m) into "
                          f"{int(np.prod(shape, dtype=float))} voxels, more than {MAX_VOXELS}: use a larger voxel")
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    return np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1), shape


def reachability_map(robot, voxel: float = 0.05, orientations: int = 32, scene=None, backend: str = "local",
                     workers: int | None = None, seed: int = 0, progress: bool = True, address: str | None = None,
                     batch_size: int = DEFAULT_BATCH, **options) -> ReachMap:
    """The reachability map of ``robot`` as a :class:`ReachMap`: the batch engine of :func:`evoik_pin.solve_many` (its
    LM rounds only, so the index is a lower bound) asked at every voxel centre, first for the position, then for
    ``orientations`` orientations (a super-Fibonacci sample of SO(3), the same for every voxel); ``index`` is the
    fraction reached, ``manipulability`` the best ``sqrt(det(J J^T))`` among the answers.

    Args:
        robot: a :class:`Robot` or anything :func:`load_robot` accepts. voxel: voxel edge (m). orientations:
            orientations asked per voxel for 6-D arms (>= 1). scene: a Scene or a scene file's path: collision-free
            answers only. backend, workers, address, progress: as for :func:`evoik_pin.solve_many`. seed: of the
            workspace sampling. batch_size: targets per call of the batch engine. **options: IK options.

    Raises:
        OptionError: a bad option (``backend``, ``workers``, ``voxel`` too small for :data:`MAX_VOXELS`, ...).
    """
    t0 = time.perf_counter()
    robot = _robot(robot)
    voxel = check_positive("voxel (m)", voxel)
    orientations = check_int("orientations", orientations, 1)
    seed = check_int("seed", seed, 0)
    batch_size = check_int("batch_size", batch_size, 1)
    workers = check_backend(backend, workers, address)
    scene = coerce_scene(robot, scene)
    if scene is not None:
        options["scene"] = scene
    check_call(robot, make_problem, "memetic", options)  # every IK option, before any work (and Ray)
    rng = np.random.default_rng(seed)
    P = robot.positions_batch(robot.random_configurations(WORKSPACE_SAMPLES, rng))
    lo, hi = P.min(axis=0), P.max(axis=0)
    planar = bool(hi[2] - lo[2] <= 1e-9 and robot.n >= 2)
    kind = "planar" if planar else ("position" if robot.n < 6 else "pose")
    centers, shape = _grid(lo - voxel, hi + voxel, voxel, float(lo[2]) if planar else None)
    M = centers.shape[0]
    engine = batch_engine(robot, make_problem, _run, "memetic", seed, options, backend, workers, address,
                          fallback=False)
    bar = ProgressBar(f"reach {robot.name}", "target", enabled=progress)

    def run(targets) -> BatchOutcome:
        """The engine on ``targets`` (Targets, or (N, 4, 4) poses), ``batch_size`` at a time."""
        parts = []
        for a in range(0, len(targets), batch_size):
            parts.append(engine.solve(targets[a:a + batch_size]))
            bar.update(len(parts[-1]))
        return BatchOutcome.concatenate(parts)

    rows = [0, 1] if planar else ("translation" if kind == "position" else "full")
    asked = 0  # pose targets (after the position pass)
    with bar:
        bar.grow(M)
        with gc_paused():
            first = ([Target.planar_target(x, y) for x, y in centers[:, :2]] if planar
                     else [Target(c) for c in centers])
        out = run(first)
        reached = out.success.copy()
        count = reached.astype(float)
        best = np.zeros(M)
        if kind != "pose":
            best[reached] = robot.manipulability_batch(out.q[reached], rows)
        else:
            count[:] = 0.0
            R = so3_samples(orientations)
            cells = np.nonzero(reached)[0]
            asked = cells.size * orientations
            bar.grow(asked)
            step = max(1, batch_size // orientations)
            for a in range(0, cells.size, step):  # voxel after voxel, every orientation of each
                part = cells[a:a + step]
                H = np.zeros((part.size, orientations, 4, 4))
                H[:, :, :3, :3] = R
                H[:, :, :3, 3] = centers[part, None, :]
                H[:, :, 3, 3] = 1.0
                res = run(H.reshape(-1, 4, 4))  # solved as an array: no Target object per pose
                ok = res.success.reshape(part.size, orientations)
                count[part] = ok.sum(axis=1)
                m = np.zeros(ok.shape)
                m[ok] = robot.manipulability_batch(res.q.reshape(part.size, orientations, -1)[ok], rows)
                best[part] = m.max(axis=1)
    n_orient = orientations if kind == "pose" else 1
    settings = {"workspace_samples": WORKSPACE_SAMPLES, "backend": backend, "workers": engine.workers,
                "position_targets": M, "pose_targets": asked,
                "batch_size": batch_size, "manipulability_rows": rows, "scene": None if scene is None else repr(scene),
                "options": {k: v for k, v in options.items() if isinstance(v, (int, float, str, bool))}}
    return ReachMap(centers, count / n_orient, best, voxel, n_orient, kind, seed, robot.name, robot.tip,
                    robot.base, shape, time.perf_counter() - t0, settings)
