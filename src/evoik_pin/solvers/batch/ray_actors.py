"""The Ray backend of :func:`evoik_pin.solve_many` (``backend="ray"``; ``pip install 'evoik_pin[ray]'``):
:class:`RayBatch` hands chunks to actors (:class:`RayPool`), each running a :class:`~.threads.BatchSolver` on one
thread; a chunk whose actor dies is re-run on a new actor, up to ``attempts`` times (a solver's own error is raised
as is). Clusters: docs/SCALE.md.
"""

from __future__ import annotations

import functools
import hashlib
import os
import pickle
import socket
import uuid
from collections import deque
from collections.abc import Callable
from urllib.parse import urlsplit

import numpy as np

from ...errors import BackendError, TargetError
from ...problem import Target
from .batch_results import BatchOutcome
from .goal_lists import source_of
from .threads import BatchSolver, ProgressBar, check_workers, chunk_bounds, gc_paused

__all__ = ["RayBatch", "RayPool", "connect", "pack_targets", "pool_for", "scene_spec", "shutdown_pool",
           "unpack_targets"]

#: Attempts per chunk before its failure is reported (an actor dying each time).
DEFAULT_ATTEMPTS = 3
#: Guided chunks for the actors (:func:`~.threads.chunk_bounds`), between these sizes (targets; a remote call costs
#: about a millisecond).
RAY_MIN_CHUNK, RAY_MAX_CHUNK = 1000, 20_000
#: Seconds to reach a cluster address before calling it unreachable.
CONNECT_TIMEOUT = 5.0
INSTALL_HINT = "pip install 'evoik_pin[ray]'"


def _probe(address: str) -> None:
    """BackendError unless something listens at a ``host:port`` / ``ray://host:port`` address (Ray's own
    connection attempt would retry for minutes)."""
    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
    if not host or port is None:
        raise BackendError(f"Ray cluster address {address!r} is not host:port, ray://host:port or 'auto'")
    try:
        socket.create_connection((host, port), timeout=CONNECT_TIMEOUT).close()
    except OSError as exc:
        raise BackendError(f"cannot reach the Ray cluster at {address!r}: {exc.strerror or exc}") from None


def connect(address: str | None = None, workers: int | None = None):
    """The ``ray`` module, initialized: connected to the cluster at ``address`` (else ``RAY_ADDRESS``; ``"auto"``:
    the one on this machine; BackendError at once when nothing answers there), else an initialized Ray as it is, else
    a local instance of ``workers`` CPUs (default every core). BackendError when Ray is not installed."""
    try:
        import ray
    except ImportError:
        raise BackendError(f"backend='ray' needs Ray, which is not installed: {INSTALL_HINT}") from None
    address = address or os.environ.get("RAY_ADDRESS") or None
    if address is not None and address != "auto":
        _probe(address)
    if ray.is_initialized():
        return ray
    kwargs = {"log_to_driver": False, "configure_logging": False}
    try:
        if address is None:
            # Ray starts its workers at nice 15, starved beside any busy process: the call's work runs at the
            # caller's priority unless the user set RAY_worker_niceness
            os.environ.setdefault("RAY_worker_niceness", "0")
            ray.init(num_cpus=check_workers(workers), include_dashboard=False, **kwargs)
        else:
            ray.init(address=address, **kwargs)
    except (ConnectionError, TimeoutError) as exc:
        raise BackendError(f"cannot reach the Ray cluster at {address!r}: {exc}") from None
    return ray


# ---------------------------------------------------------------------- what travels to the actors
def pack_targets(targets: list[Target]) -> dict:
    """Targets as arrays (cheaper to pickle than Target objects): ``planar``, ``yaw`` (NaN: none),
    ``has_rotation`` (N,) and ``position`` (N, 3) (planar: (x, y, 0)), ``rotation`` (N, 3, 3)."""
    N = len(targets)
    position = np.zeros((N, 3))
    rotation = np.tile(np.eye(3), (N, 1, 1))
    planar = np.fromiter((t.planar for t in targets), dtype=bool, count=N)
    has_rotation = np.fromiter((t.rotation is not None for t in targets), dtype=bool, count=N)
    yaw = np.array([np.nan if t.yaw is None else t.yaw for t in targets])
    for i, t in enumerate(targets):
        position[i, :t.position.shape[0]] = t.position
    if has_rotation.any():
        rotation[has_rotation] = [t.rotation for t in targets if t.rotation is not None]
    return {"position": position, "rotation": rotation, "planar": planar, "has_rotation": has_rotation, "yaw": yaw}


def unpack_targets(packed) -> list[Target]:
    """The targets :func:`pack_targets` packed."""
    P, R, planar, has_rotation, yaw = (packed[k] for k in ("position", "rotation", "planar", "has_rotation", "yaw"))
    N = P.shape[0]
    if has_rotation.all():
        H = np.zeros((N, 4, 4))
        H[:, :3, :3], H[:, :3, 3], H[:, 3, 3] = R, P, 1.0
        return Target.from_poses(H)
    return [Target(P[i, :2], planar=True, yaw=None if np.isnan(yaw[i]) else float(yaw[i])) if planar[i]
            else Target(P[i], R[i] if has_rotation[i] else None) for i in range(N)]


def scene_spec(scene) -> dict | None:
    """What rebuilds ``scene`` on another process (its Pinocchio data does not pickle): settings and obstacles."""
    if scene is None:
        return None
    return {"self_collision": scene.self_collision, "srdf": scene.srdf,
            "obstacles": [(o.kind, o.name, dict(o.params), o.pose.homogeneous.copy())
                          for o in scene.obstacles.values()]}


def build_scene(robot, spec: dict):
    """The :class:`~evoik_pin.scene.Scene` of ``robot`` that :func:`scene_spec` describes."""
    import pinocchio as pin

    from ...scene import Scene

    scene = Scene(robot, self_collision=spec["self_collision"], srdf=spec["srdf"])
    for kind, name, params, pose in spec["obstacles"]:
        getattr(scene, f"add_{kind}")(name, pose=pin.SE3(pose), **params)
    return scene


class ChunkWorker:
    """A Ray actor's state: the robot (received once) and the solver of the call in progress."""

    def __init__(self, robot) -> None:
        self.robot = robot
        self._key = None
        self._solver: BatchSolver | None = None

    def solve(self, key: str, job: tuple, packed: dict, Q0: np.ndarray | None, offset: int,
              crash: bool = False) -> BatchOutcome:
        """Solve one chunk (targets ``offset``, ``offset + 1``, ... of call ``key``; ``job``: the
        :class:`~.threads.BatchSolver`'s keywords but its options, its options but the scene, the scene's
        :func:`scene_spec`). ``crash``: exit the process at once instead (tests: an actor dying mid-run)."""
        if crash:
            os._exit(1)
        if key != self._key:
            solver_args, options, scene = job
            if scene is not None:
                options = {**options, "scene": build_scene(self.robot, scene)}
            self._solver = BatchSolver(self.robot, options=options, **solver_args)
            self._key = key
        if isinstance(packed, (np.ndarray, list)):  # poses (no Target object per pose) or goal lists, as they are
            targets = packed
        else:
            with gc_paused():
                targets = unpack_targets(packed)
        out = self._solver.solve(targets, Q0, offset=offset)
        for r in out.singles.values():  # a lazy min_distance holds this process's scene: the driver re-attaches
            r.distance_source = None
        return out


class RayPool:
    """Actors holding one robot, kept between calls (an actor takes seconds to start); one alive at a time."""

    def __init__(self, ray, robot, workers: int, key: tuple) -> None:
        self.ray, self.key, self.workers = ray, key, workers
        self._robot = ray.put(robot)  # pickled once into the object store
        self._actor_class = ray.remote(num_cpus=1)(ChunkWorker)
        self.actors = [self._actor_class.remote(self._robot) for _ in range(workers)]
        self.replaced = 0  # actors replaced after dying

    def replace(self, actor):
        """A new actor in place of ``actor`` (dead, or to be killed)."""
        self.retire(actor)
        self.replaced += 1
        self.actors.append(self._actor_class.remote(self._robot))
        return self.actors[-1]

    def retire(self, actor) -> None:
        if actor in self.actors:
            self.actors.remove(actor)
        try:
            self.ray.kill(actor)
        except Exception:  # noqa: BLE001 - already gone, or Ray already shut down
            pass

    def close(self) -> None:
        for actor in list(self.actors):
            self.retire(actor)


_POOL: list[RayPool] = []  # the live pool, if any


def pool_for(robot, workers: int | None = None, address: str | None = None) -> RayPool:
    """The actor pool for ``robot`` (by its pickled content) and ``workers`` (default every CPU of the cluster): the
    kept one when it matches, else a new one (the previous one closed: its actors hold CPUs)."""
    ray = connect(address, workers)
    workers = workers or max(1, int(ray.cluster_resources().get("CPU", 1)))
    key = (ray.get_runtime_context().get_job_id(), hashlib.sha1(pickle.dumps(robot)).hexdigest(), workers)
    if _POOL and _POOL[0].key == key:
        return _POOL[0]
    shutdown_pool()
    _POOL.append(RayPool(ray, robot, workers, key))
    return _POOL[0]


def shutdown_pool() -> None:
    """Stop the kept actors (``ray.shutdown()`` does too)."""
    while _POOL:
        _POOL.pop().close()


class RayBatch:
    """One call's work on a :class:`RayPool`: chunks of targets to the actors, outcomes back in target order.

    Args:
        robot, make_problem, run, method, entropy, options, fallback, choose, prefer: as
            :class:`~.threads.BatchSolver`'s.
        workers: actors (one CPU each); default every CPU of the cluster.
        address: see :func:`connect`. chunk_size: targets per chunk (default: guided chunks, ``RAY_MIN_CHUNK`` to
            ``RAY_MAX_CHUNK`` targets, shrinking toward the end).
    """

    def __init__(self, robot, make_problem: Callable, run: Callable, method: str, entropy: int, options: dict,
                 fallback: bool = True, workers: int | None = None, address: str | None = None,
                 chunk_size: int | None = None, choose: Callable | None = None, prefer: str | None = None) -> None:
        solver_args = dict(make_problem=make_problem, run=run, method=method, entropy=entropy, fallback=fallback,
                           choose=choose, prefer=prefer)
        # the driver's own solver checks every option before any actor sees them, and judges scenes at the end
        self._local = BatchSolver(robot, options=options, **solver_args)
        self.pool = pool_for(robot, workers, address)
        self.ray, self.workers = self.pool.ray, self.pool.workers
        self.chunk_size = chunk_size
        options = self._local.options  # checked, the scene read from its file if one was named
        self._scene = options.get("scene")
        remote_options = {k: v for k, v in options.items() if k != "scene"}
        self._key = uuid.uuid4().hex
        self._job = self.ray.put((solver_args, remote_options, scene_spec(self._scene)))
        self.crash_hook: set[int] = set()  # tests: chunks whose first attempt kills its actor

    @property
    def template(self):
        """The call's problem (the driver's; its scene judges the batched answers); None before :meth:`solve`."""
        return self._local.template

    def solve(self, targets, Q0: np.ndarray | None = None, offset: int = 0, progress: bool = False) -> BatchOutcome:
        """:meth:`.threads.BatchSolver.solve` on the actors."""
        ray, pool = self.ray, self.pool
        source = source_of(self._local.robot, targets)
        if self._local.template is None:  # every option checked here, before the actors see them
            self._local._prepare(source.chunk(0, 1)[0])
        poses = source.poses
        N, size = len(source), self.chunk_size
        chunks = ([(a, min(a + size, N)) for a in range(0, N, size)] if size
                  else chunk_bounds(N, self.workers, RAY_MIN_CHUNK, RAY_MAX_CHUNK))
        todo = deque((k, 0) for k in range(len(chunks)))  # (chunk, attempt)
        idle = deque(pool.actors)
        running: dict = {}  # future -> (chunk, attempt, actor)
        parts: dict[int, BatchOutcome] = {}
        with ProgressBar("solve_many (ray)", enabled=progress) as bar:
            bar.grow(len(chunks))
            while todo or running:
                while todo and idle:
                    k, attempt = todo.popleft()
                    actor = idle.popleft()
                    a, b = chunks[k]
                    # poses and goal lists go as they are (the actor makes and checks the Target objects)
                    packed = (poses[a:b] if poses is not None else source.chunk(a, b) if source.goals
                              else pack_targets(source.chunk(a, b)))
                    future = actor.solve.remote(self._key, self._job, packed, None if Q0 is None else Q0[a:b],
                                                offset + a, crash=k in self.crash_hook and attempt == 0)
                    running[future] = (k, attempt, actor)
                done, _ = ray.wait(list(running), num_returns=1)
                for future in done:
                    k, attempt, actor = running.pop(future)
                    try:
                        parts[k] = ray.get(future)
                        bar.update(1)
                    except ray.exceptions.RayActorError as exc:  # the actor died: a new one re-runs the chunk
                        if attempt + 1 >= DEFAULT_ATTEMPTS:
                            pool.retire(actor)
                            raise BackendError(f"chunk {k} (targets {chunks[k][0]}-{chunks[k][1] - 1}) failed "
                                               f"{DEFAULT_ATTEMPTS} times: its Ray actor died ({exc})") from None
                        actor = pool.replace(actor)
                        todo.appendleft((k, attempt + 1))
                    except TargetError:  # a bad pose in a chunk sent as it was: name it by its index in the call
                        source.check()
                        raise
                    idle.append(actor)
        out = BatchOutcome.concatenate([parts[k] for k in range(len(chunks))])
        if self._scene is not None:
            for r in out.singles.values():
                r.distance_source = functools.partial(self._scene.distance, r.q.copy())
        return out
