"""Run a dataset: the samples not yet finished, on local worker processes or Ray tasks.

Each local worker is a separate process with its own Blender (``bpy``), restarted after
``render.recycle_every`` samples so memory stays flat over long runs. The parent appends a
sample's manifest line only once the worker has published its folder; see ``store`` for why
an interrupted run (Ctrl-C or a kill) resumes with nothing lost, duplicated or half-written.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import sys
import tempfile
import time
from collections.abc import Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from avatar.dataset import sampling, store
from avatar.dataset.config import Config, avatar_version
from avatar.dataset.people import COCO_KEYPOINTS, COCO_SKELETON, PARTS
from avatar.errors import AvatarError

log = logging.getLogger(__name__)

CATEGORIES = [{"id": 1, "name": "person", "supercategory": "person",
               "keypoints": list(COCO_KEYPOINTS), "skeleton": COCO_SKELETON}]  # fmt: skip


@dataclass
class RunReport:
    """What a run did: samples rendered now, already there, failed (index -> message),
    its seconds, and when each rendered sample came in (seconds from the start, in order:
    the steady rate, once the workers' start-up is behind them, is what millions of
    samples cost)."""

    rendered: int = 0
    skipped: int = 0
    failed: dict[int, str] = field(default_factory=dict)
    seconds: float = 0.0
    finished_at: list[float] = field(default_factory=list)

    def steady_rate(self, skip: int) -> float:
        """Samples/s between the ``skip``-th rendered sample and the last (0 when fewer
        than two are left to time)."""
        times = self.finished_at[max(skip, 1) - 1 :]
        if len(times) < 2 or times[-1] <= times[0]:
            return 0.0
        return (len(times) - 1) / (times[-1] - times[0])


def run(config: Config, out: str | os.PathLike[str], workers: int = 1, engine: str = "local",
        config_text: str | None = None, progress: bool = False) -> RunReport:  # fmt: skip
    """Render samples 0..config.count-1 that ``out`` lacks, then write ``coco.json``.

    Raises AvatarError before rendering anything when the config refers to something that
    does not exist, or when ``out`` holds a dataset made from another config.
    """
    sampling.check(config)
    out = Path(out)
    _prepare(out, config, config_text)
    finished = store.done(out)
    todo = [i for i in range(config.count) if i not in finished]
    report = RunReport(skipped=config.count - len(todo))
    start = time.perf_counter()
    if todo:
        if engine == "ray":
            from avatar.dataset.ray_engine import render as ray_render

            results = ray_render(config, out, todo, workers)
        elif engine == "local":
            results = _local(config, out, todo, workers)
        else:
            raise AvatarError(f"unknown engine {engine!r}; use local or ray")
        _collect(out, results, report, len(todo), progress, start)
    report.seconds = time.perf_counter() - start
    finished = store.done(out)
    ids = sorted(i for i in finished if i < config.count)
    store.write_json(out / "coco.json", store.coco(out, store.read_metas(out, ids), CATEGORIES))
    return report


def _prepare(out: Path, config: Config, config_text: str | None) -> None:
    """Create the folder, or check it was made from this same config (resuming)."""
    info_path = out / "dataset.json"
    if info_path.exists():
        import json

        info = json.loads(info_path.read_text())
        if info.get("config_digest") != config.digest:
            raise AvatarError(f"{out} holds a dataset made from another config; "
                              "use a new output folder")  # fmt: skip
        return
    out.mkdir(parents=True, exist_ok=True)
    (out / "samples").mkdir(exist_ok=True)
    if config_text is not None:
        store.atomic.write_text(out / "config.toml", config_text)
    store.write_json(info_path, _info(config))


def _info(config: Config) -> dict:
    return {
        "avatar": avatar_version(), "config_digest": config.digest, "seed": config.seed,
        "count": config.count, "parts": ["none", *PARTS], "coco_keypoints": list(COCO_KEYPOINTS),
        "coco_skeleton": COCO_SKELETON,
        "instance_ids": "person * 100 + item + 1 (item 0: body and eyes; 1..: garments in "
                        "wearing order); 0: background and floor",
        "camera": "K (3x3, pixels) and world_to_camera (4x4) in OpenCV axes: x right, y down, "
                  "z forward; pixel (0, 0) is the centre of the top-left pixel; world in "
                  "metres, Z up. coco.json keypoints use COCO's pixel corners (x = u + 0.5)",
        "depth": "depth.exr channel Z: planar depth along the optical axis, metres, float32; "
                 "inf where nothing was hit",
        "normals": "normals.exr channels X, Y, Z: unit normals in the camera frame (OpenCV)",
        "files": list(store.SAMPLE_FILES), "licence": "CC0-1.0 (MakeHuman assets CC0)",
    }  # fmt: skip


Result = tuple[int, dict | None, str | None]  # (index, manifest entry, error)


def _local(config: Config, out: Path, todo: list[int], workers: int) -> Iterable[Result]:
    """Render ``todo`` on ``workers`` processes, yielding results as they finish."""
    threads = render_threads(workers)
    with thread_limits(threads):  # workers start (and restart) while the pool runs
        yield from _pooled(config, out, todo, workers, threads)


def _pooled(config: Config, out: Path, todo: list[int], workers: int,
            threads: int) -> Iterable[Result]:  # fmt: skip
    context = multiprocessing.get_context("spawn")  # a fresh Blender per worker
    slots = context.Array("i", max(1, workers))  # the pid holding each share of the cores
    pool = ProcessPoolExecutor(max_workers=max(1, workers), mp_context=context,
                               max_tasks_per_child=config.render.recycle_every,
                               initializer=hold_to_share, initargs=(slots,))  # fmt: skip
    pending: dict[Future, int] = {}
    queue = list(reversed(todo))
    try:
        while queue or pending:
            while queue and len(pending) < 2 * max(1, workers):  # a short queue per worker
                index = queue.pop()
                pending[pool.submit(_render_one, config, index, str(out), threads)] = index
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in finished:
                index = pending.pop(future)
                try:
                    yield future.result()
                except Exception as exc:  # noqa: BLE001 - a crashed worker: report, go on
                    yield index, None, f"worker failed: {exc.__class__.__name__}: {exc}"
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def hold_to_share(slots) -> None:
    """Worker initializer: hold this process to a share of the cores no other live worker
    holds (Linux; elsewhere nothing). ``slots``: a shared array, one entry per worker, of
    the pid holding that share (0: none). Told how many threads to start, Cycles, OpenMP and
    OpenBLAS still ran on every core, as does Blender's task scheduler (scene sync, BVH
    builds), so two workers took time from each other's renders; held to disjoint cores,
    every pool a worker starts sizes itself to its share. A recycled worker takes the share
    its predecessor left."""
    if len(slots) < 2 or not hasattr(os, "sched_setaffinity"):
        return
    cores = sorted(os.sched_getaffinity(0))
    if len(cores) < len(slots):
        return
    with slots.get_lock():
        free = [i for i, pid in enumerate(slots) if pid == 0 or not _alive(pid)]
        share = free[0] if free else os.getpid() % len(slots)
        slots[share] = os.getpid()
    os.sched_setaffinity(0, cores[share :: len(slots)])


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process took the pid: not a worker of ours
        return False
    return True


# Native thread pools a worker's libraries start with one thread per core unless told.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


@contextmanager
def thread_limits(threads: int) -> Iterator[None]:
    """Spawned workers limited to ``threads`` native threads each (OpenMP: pykdtree's
    searches; OpenBLAS/MKL: numpy), as their Cycles is: otherwise every worker's OpenMP
    pool has a thread per core, spinning after each search, and two workers on two cores
    take time from each other's renders. The variables are read when a library loads, so
    they are set in this process's environment, which spawned workers inherit, for as long
    as the pool may start workers (it restarts them after ``recycle_every`` samples); a
    value the user set is kept. 0: no limit (one worker)."""
    saved = {name: os.environ.get(name) for name in THREAD_VARIABLES}
    if threads > 0:
        for name in THREAD_VARIABLES:
            os.environ.setdefault(name, str(threads))
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def render_threads(workers: int, cores: int | None = None) -> int:
    """Cycles threads for each of ``workers`` processes sharing this machine's cores; 0 for a
    single worker (Cycles' own choice: every core). Each worker's Cycles would otherwise
    start a thread per core, so two workers on two cores fought over both and a second
    worker added a third of a worker's rate instead of nearly one."""
    if workers <= 1:
        return 0
    return max(1, (cores or os.cpu_count() or 1) // workers)


def _render_one(config: Config, index: int, out: str, threads: int = 0) -> Result:
    """Worker side: render one sample with ``threads`` Cycles threads (0: all cores);
    errors come back as text (never kill the pool)."""
    # Blender writes its user config at import: a private folder, not the user's
    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-bpy-"))
    if "bpy" not in sys.modules:
        # A spawned worker inherits its parent's sys.path: where the parent had imported bpy,
        # that holds Blender's own scripts folders, whose pure-Python ``bpy`` would shadow
        # the module's (and fail on ``_bpy``). Blender adds them back when it starts.
        marker = f"{os.sep}bpy{os.sep}"
        sys.path[:] = [p for p in sys.path if not (marker in p and "scripts" in p)]
    from avatar.dataset.worker import render_sample

    try:
        return index, render_sample(config, index, out, threads), None
    except AvatarError as exc:
        return index, None, str(exc)


def _collect(out: Path, results: Iterable[Result], report: RunReport, total: int,
             progress: bool, start: float) -> None:  # fmt: skip
    from tqdm import tqdm

    with tqdm(total=total, unit="sample", disable=not progress, file=sys.stderr) as bar:
        for index, entry, error in results:
            if entry is not None:
                store.append(out, entry)
                report.rendered += 1
                report.finished_at.append(time.perf_counter() - start)
            else:
                report.failed[index] = error or "failed"
                log.error("sample %d: %s", index, error)
            bar.update()

