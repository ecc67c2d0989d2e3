"""Dataset throughput and memory, against anchors measured in the same run.

    python bench/dataset.py [--count 16] [--resolution 256] [--samples 16] [--rss 0]
                            [--repeat 1] [--overhead-only | --workers-only]

1. label overhead: samples/s with every label against the anchor, a bare Cycles render of
   the same scenes (same people, camera, lights; RGB only), on one worker in-process, and
   the label pass's own seconds (``--overhead-only``: this part alone);
2. workers: 1 -> 2 local worker processes, each rendering on its share of the cores
   (efficiency = rate(2) / (2 * rate(1)), the single worker on one core's share, as each
   of the two has: its threads limited and the process held to that many cores), and the
   speed-up of 2 workers over 1 worker on every core;
   and the machine's own ceiling, measured in the same run: two CPU-bound loops on two
   cores at once against one alone (a VM's two cores may share one physical core);
   ``--repeat N`` measures the three N times in turn and prints each round and the median
   (a VM whose host shares its cores varies 10-30% from one run to the next);
3. engines: local vs Ray (a local cluster), same samples;
4. --rss N: the worker's resident memory over N samples (one process, no recycling), the
   curve printed every 10 samples: it should stay within 10% of its value after 50.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from avatar.clothes import disk_cache
from avatar.dataset import config as dataset_config
from avatar.dataset import people, runner, sampling, worker


def _config(args, count: int, extra: str = "") -> dataset_config.Config:
    text = dataset_config.EXAMPLE + extra
    return dataset_config.loads(text, "bench.toml", count=count, samples=args.samples,
                                resolution=(args.resolution, args.resolution))  # fmt: skip


def bare_vs_labelled(args, folder: Path) -> tuple[float, float, float, float]:
    """(bare s/sample, labelled s/sample, median over the samples of labelled / bare, mean
    s of ``Stage.render_labels``) in this process, same scenes, alternating (the median of
    the pairs is not thrown by one sample that met a busy host)."""
    from avatar.blender import labels as blender_labels

    c = _config(args, args.count)
    bare, labelled = np.zeros(args.count), np.zeros(args.count)
    worker.render_sample(c, args.count, folder)  # warm: garments built, Blender started
    label_pass: list[float] = []
    render_labels = blender_labels.Stage.render_labels

    def timed(stage):  # the label render, read back and decoded
        start = time.perf_counter()
        try:
            return render_labels(stage)
        finally:
            label_pass.append(time.perf_counter() - start)

    blender_labels.Stage.render_labels = timed  # type: ignore[method-assign]
    for i in range(args.count):
        for step in ((0, 1) if i % 2 else (1, 0)):  # alternate which one meets warm caches
            start = time.perf_counter()
            if step:
                worker.render_sample(c, i, folder)  # everything: people, RGB, labels, files
                labelled[i] = time.perf_counter() - start
                continue
            spec = sampling.sample(c, i)
            posed = [people.pose_person(p) for p in spec.people]
            items = [blender_labels.Item(part, 1) for person in posed for part in person.parts]
            stage = worker._STAGE[0]
            stage.build(items, spec.camera, spec.light, spec.background)
            stage.render_rgb(folder / "bare.png", spec.engine, spec.samples, False)
            bare[i] = time.perf_counter() - start
    blender_labels.Stage.render_labels = render_labels  # type: ignore[method-assign]
    paired = float(np.median(labelled / bare))
    return bare.mean(), labelled.mean(), paired, float(np.mean(label_pass))


def rate(args, workers: int, engine: str, folder: Path,
         threads: int | None = None) -> tuple[float, float]:  # fmt: skip
    """(samples/s of a fresh run end to end, its steady samples/s once each worker's first
    sample, which carries its start-up, is in: ``RunReport.steady_rate``); ``threads``: each
    local worker's Cycles threads (default: the runner's share of the cores)."""
    c = _config(args, args.count)
    shares = runner.render_threads
    cores = os.sched_getaffinity(0)
    if threads is not None:  # the parent decides the workers' threads: set it there
        runner.render_threads = lambda workers, cores=None: threads  # type: ignore[assignment]
        # ... and on that many cores only (workers inherit it): the anchor worker's numpy
        # and OpenMP searches would otherwise also use the core the other worker has.
        os.sched_setaffinity(0, sorted(cores)[:threads])
    shutil.rmtree(folder, ignore_errors=True)
    # Every run starts with an empty garment cache of its own: each pays the builds once,
    # as a fresh dataset run on a fresh machine does (its workers share them).
    os.environ[disk_cache.ENV_ROOT] = str(folder.with_name(folder.name + "-garments"))
    shutil.rmtree(os.environ[disk_cache.ENV_ROOT], ignore_errors=True)
    start = time.perf_counter()
    try:
        with runner.thread_limits(threads or 0):
            report = runner.run(c, folder, workers=workers, engine=engine)
    finally:
        runner.render_threads = shares  # type: ignore[assignment]
        os.sched_setaffinity(0, cores)
    assert not report.failed, report.failed
    return args.count / (time.perf_counter() - start), report.steady_rate(workers)


def _spin(core: int) -> float:
    """Seconds of a fixed pure-Python loop on one core (no memory traffic to speak of)."""
    os.sched_setaffinity(0, {core})
    start, total = time.perf_counter(), 0
    for i in range(12_000_000):
        total += i * i
    return time.perf_counter() - start


def _stream(core: int) -> float:
    """Seconds of a fixed memory-bound loop on one core: numpy sums over arrays far larger
    than the caches (what a renderer's BVH and image buffers ask of the memory)."""
    os.sched_setaffinity(0, {core})
    a, b = np.ones(8_000_000), np.ones(8_000_000)
    out = np.empty_like(a)
    start = time.perf_counter()
    for _ in range(60):
        np.add(a, b, out=out)
    return time.perf_counter() - start


def machine_ceiling(repeat: int = 3, work=_spin) -> float:
    """What this machine gives two busy processes: the rate of each of two loops on two
    cores at once over one loop alone (1.0 on two real cores; less where the cores share a
    physical core, the memory bus, or the host throttles). ``work``: ``_spin`` (CPU-bound)
    or ``_stream`` (memory-bound). The workers' efficiency cannot exceed it."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    cores = sorted(os.sched_getaffinity(0))[:2]
    ratios = []
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        for _ in range(repeat):
            alone = pool.submit(work, cores[0]).result()
            both = [f.result() for f in [pool.submit(work, c) for c in cores]]
            ratios.append(alone / max(both))
    return sorted(ratios)[len(ratios) // 2]


def rss_curve(args, folder: Path) -> list[tuple[int, float]]:
    """(samples done, RSS MB) of this process rendering ``args.rss`` samples."""
    c = _config(args, args.rss)
    out = []
    for i in range(args.rss):
        worker.render_sample(c, i, folder)
        if (i + 1) % 10 == 0:
            out.append((i + 1, _rss_mb()))
            print(f"  {i + 1:5d} samples: RSS {out[-1][1]:.0f} MB", flush=True)
    return out


def _rss_mb() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=12)
    parser.add_argument("--resolution", type=int, default=256)
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--rss", type=int, default=0, help="samples for the memory curve")
    parser.add_argument("--skip-ray", action="store_true")
    parser.add_argument("--repeat", type=int, default=1, help="rounds of the workers' rates")
    parser.add_argument("--overhead-only", action="store_true",
                        help="only the label overhead (part 1)")
    parser.add_argument("--workers-only", action="store_true",
                        help="only the workers and engines (parts 2 and 3)")
    args = parser.parse_args()
    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-bpy-"))
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        os.environ[disk_cache.ENV_ROOT] = str(root / "garments")  # leave the user's alone
        print(f"{args.count} samples, {args.resolution}x{args.resolution}, {args.samples} spp, "
              f"{os.cpu_count()} CPUs, Python {sys.version.split()[0]}")  # fmt: skip
        if args.count == 0:  # --count 0: the memory curve only
            args.skip_ray = True
        else:
            _throughput(args, root)
        if args.rss:
            curve = rss_curve(args, root / "rss")
            base = next((mb for n, mb in curve if n >= 50), curve[0][1])
            late = [(n, mb) for n, mb in curve if n >= 50]
            x, y = np.array(late, dtype=float).T
            slope = np.polyfit(x, y, 1)[0] * 100 if len(late) > 2 else 0.0
            print(f"RSS after {curve[-1][0]} samples: {curve[-1][1]:.0f} MB, "
                  f"{100 * (curve[-1][1] / base - 1):+.1f}% of the value after 50; highest "
                  f"after 50: {100 * (max(mb for _, mb in late) / base - 1):+.1f}%; trend "
                  f"{slope:+.1f} MB per 100 samples")  # fmt: skip
    return 0


def _throughput(args, root: Path) -> None:
    if not args.workers_only:
        _overhead(args, root)
    if args.overhead_only:
        return
    _workers(args, root)


def _overhead(args, root: Path) -> None:
    bare, labelled, paired, label_pass = bare_vs_labelled(args, root / "inproc")
    print(f"bare Cycles render (anchor): {bare:.2f} s/sample; with every label: "
          f"{labelled:.2f} s/sample; label overhead {100 * (labelled / bare - 1):.0f}% "
          f"(median of the {args.count} pairs: {100 * (paired - 1):.0f}%); the label pass "
          f"itself {label_pass:.3f} s/sample")  # fmt: skip


def _workers(args, root: Path) -> None:
    share = max(1, (os.cpu_count() or 1) // 2)
    rounds = []
    for r in range(args.repeat):
        one_share, steady_one = rate(args, 1, "local", root / "w1s", threads=share)
        one, _ = rate(args, 1, "local", root / "w1")
        two, steady_two = rate(args, 2, "local", root / "w2")
        ceiling, memory = machine_ceiling(), machine_ceiling(work=_stream)
        rounds.append((two / (2 * one_share), steady_two / (2 * steady_one), ceiling, two / one,
                       memory))  # fmt: skip
        print(f"round {r + 1}: local engine: 1 worker on {share} thread(s) {one_share:.3f} "
              f"samples/s, 2 workers on {share} each {two:.3f} samples/s: efficiency "
              f"{rounds[-1][0]:.2f} end to end, {rounds[-1][1]:.2f} steady (after each "
              f"worker's first sample: {steady_one:.3f} and {steady_two:.3f} samples/s); 1 "
              f"worker on every core {one:.3f} samples/s: 2 workers {rounds[-1][3]:.2f}x "
              f"that; machine ceiling (anchors): two CPU-bound loops on two cores each run at "
              f"{ceiling:.2f} of one alone, two memory-bound ones at {memory:.2f}",
              flush=True)  # fmt: skip
    efficiency, steady, ceiling, speedup, memory = np.median(np.array(rounds), axis=0)
    print(f"median of {len(rounds)} round(s): efficiency {efficiency:.2f} end to end, "
          f"{steady:.2f} steady (goal >= 0.85), machine ceiling {ceiling:.2f} CPU-bound, "
          f"{memory:.2f} memory-bound, 2 workers {speedup:.2f}x 1 worker on every core; "
          f"steady efficiency / CPU ceiling per round "
          f"{', '.join(f'{e / c:.2f}' for _, e, c, _, _ in rounds)}")  # fmt: skip
    if not args.skip_ray:
        ray, _ = rate(args, 2, "ray", root / "ray")
        print(f"ray engine (local cluster, 2 CPUs): {ray:.3f} samples/s = "
              f"{ray / two:.2f}x the local engine")  # fmt: skip


if __name__ == "__main__":
    sys.exit(main())
