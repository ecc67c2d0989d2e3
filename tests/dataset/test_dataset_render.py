"""A small dataset rendered for real (pip bpy, Cycles), its labels checked against the
geometry they claim to describe, loaded by pycocotools, resumed after a kill."""

from __future__ import annotations

import importlib.util
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from avatar.clothes import disk_cache

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("bpy") is None or importlib.util.find_spec("OpenEXR") is None
    or importlib.util.find_spec("pycocotools") is None,
    reason="needs bpy, OpenEXR and pycocotools (the dataset extra)",
)  # fmt: skip

CONFIG = """
seed = 3
count = 3
[render]
resolution = [96, 80]
samples = 2
recycle_every = 2
[people]
count = [1, 2]
[motion]
clips = ["walk"]
pose_probability = 0.3
poses = ["a-pose", "t-pose"]
[camera]
distance = [3.2, 4.0]
focal_mm = [35.0, 45.0]
[clothes]
tops = ["tshirt", "hoodie"]
bottoms = ["jeans", "shorts"]
shoes = ["shoes"]
hair = ["hair-short", "hair-long"]
face = ["eyebrows"]
"""


@pytest.fixture(scope="module")
def dataset(tmp_path_factory, model):
    from avatar.dataset import config, runner

    out = tmp_path_factory.mktemp("ds")
    (out.parent / "ds.toml").write_text(CONFIG)
    c = config.load(out.parent / "ds.toml")
    # an empty garment cache: this run builds every garment and writes it; the resumed run
    # below reads them back, and its labels must equal these bytes
    saved = os.environ.get(disk_cache.ENV_ROOT)
    os.environ[disk_cache.ENV_ROOT] = str(out / "garments")
    report = runner.run(c, out / "set", workers=1, config_text=CONFIG)
    assert report.rendered == 3 and not report.failed, report.failed
    assert len(list((out / "garments").rglob("*.pickle"))) >= 4  # the workers' builds
    # when each sample came in: rising, within the run (the steady rate is timed on them)
    times = report.finished_at
    assert len(times) == 3 and 0 < times[0] < times[1] < times[2] <= report.seconds
    assert report.steady_rate(1) == pytest.approx(2 / (times[2] - times[0]))
    yield c, out / "set"
    if saved is None:
        os.environ.pop(disk_cache.ENV_ROOT, None)
    else:
        os.environ[disk_cache.ENV_ROOT] = saved


def _posed(c, index):
    from avatar.dataset import people, sampling

    return [people.pose_person(p) for p in sampling.sample(c, index).people]


def _labels(folder: Path):
    from PIL import Image

    from avatar.io import exr

    instance = np.array(Image.open(folder / "instances.png"))
    parts = np.array(Image.open(folder / "parts.png"))
    depth = exr.read(folder / "depth.exr")["Z"]
    return instance, parts, depth, json.loads((folder / "meta.json").read_text())


def test_folder_is_complete_and_validates(dataset):
    from avatar.dataset import store

    _, out = dataset
    assert store.validate(out) == []
    lines = (out / "manifest.jsonl").read_text().splitlines()
    assert sorted(json.loads(line)["id"] for line in lines) == [0, 1, 2]
    info = json.loads((out / "dataset.json").read_text())
    assert info["parts"][0] == "none" and len(info["coco_keypoints"]) == 17


def test_coco_file_loads_and_evaluates_perfectly_against_itself(dataset):
    from pycocotools.coco import COCO
    from pycocotools.cocoeval import COCOeval

    _, out = dataset
    gt = COCO(str(out / "coco.json"))
    assert len(gt.getImgIds()) == 3 and len(gt.getAnnIds()) >= 3
    for ann in gt.loadAnns(gt.getAnnIds()):
        mask = gt.annToMask(ann)
        assert mask.sum() == ann["area"]
    dets = [dict(a, score=1.0) for a in gt.loadAnns(gt.getAnnIds())]
    for kind in ("keypoints", "segm", "bbox"):
        evaluation = COCOeval(gt, gt.loadRes(dets), kind)
        evaluation.evaluate()
        evaluation.accumulate()
        evaluation.summarize()
        assert evaluation.stats[0] == pytest.approx(1.0), kind


def test_visible_keypoints_land_inside_their_persons_mask(dataset):
    from avatar.dataset.annotate import person_of

    _, out = dataset
    hits = total = 0
    for i in range(3):
        instance, _, _, meta = _labels(out / "samples" / f"{i:08d}")
        owner = person_of(instance)
        h, w = instance.shape
        for p, person in enumerate(meta["people"]):
            for u, v, vis in person["keypoints_2d"]:
                if vis == 2:
                    total += 1
                    r, c = int(round(v)), int(round(u))
                    window = owner[max(r - 1, 0): r + 2, max(c - 1, 0): c + 2]
                    hits += bool((window == p).any())
    assert total > 20 and hits / total > 0.97, (hits, total)


def test_depth_lands_on_the_posed_surfaces_and_ids_name_their_mesh(dataset):
    """Every labelled pixel's depth, back-projected through K and world_to_camera, lies on
    the surface of the mesh its instance id names (mm level)."""
    from avatar.camera import unproject
    from avatar.dataset.annotate import instance_id

    c, out = dataset
    checked = 0
    for i in range(3):
        folder = out / "samples" / f"{i:08d}"
        instance, _, depth, meta = _labels(folder)
        world = unproject(depth, np.array(meta["K"]), np.array(meta["world_to_camera"]))
        for p, person in enumerate(_posed(c, i)):
            items = [(instance_id(p, 0), person.parts[0])]
            items += [(instance_id(p, k - 1), part) for k, part in enumerate(person.parts)
                      if k >= 2]  # fmt: skip
            for ident, part in items:
                pixels = world[instance == ident]
                if len(pixels) < 5:
                    continue
                d = _distance_to_mesh(pixels, part.mesh)
                assert np.median(d) < 0.0005 and np.mean(d < 0.003) > 0.97, (i, part.name)
                checked += 1
    assert checked >= 6


def _distance_to_mesh(points: np.ndarray, mesh) -> np.ndarray:
    """(N,) exact distance of each point to the mesh's triangles (every triangle tested:
    hair cards cross each other too densely for a nearest-vertex search)."""
    from avatar.geometry import collision

    tri = mesh.vertices[mesh.triangles()].astype(np.float64)  # (T, 3, 3)
    out = np.empty(len(points))
    for k, p in enumerate(points.astype(np.float64)):
        bary = collision.closest_on_triangles(p[None], tri[:, 0], tri[:, 1], tri[:, 2])
        closest = np.einsum("tk,tkd->td", bary, tri)
        out[k] = np.sqrt(((closest - p) ** 2).sum(axis=1)).min()
    return out


def test_parts_label_skin_and_clothes_of_each_person(dataset):
    _, out = dataset
    for i in range(3):
        instance, parts, _, _ = _labels(out / "samples" / f"{i:08d}")
        person = instance > 0
        assert np.all(parts[~person] == 0)
        assert np.mean(parts[person] > 0) > 0.97
        assert set(np.unique(parts[person])) <= set(range(1, 16))


def test_killed_run_resumes_to_the_same_labels(dataset, tmp_path):
    """SIGKILL the command mid-run, run it again: the set equals the clean run's (same
    label bytes), with no duplicate or partial sample. Its workers read the garments the
    clean run built from the cache on disk, so the bytes also show a cached garment renders
    as a built one."""
    c, clean = dataset
    config_path = tmp_path / "ds.toml"
    config_path.write_text(CONFIG)
    out = tmp_path / "set"
    cache = Path(os.environ[disk_cache.ENV_ROOT])
    builds = {p: p.stat().st_mtime_ns for p in cache.rglob("*.pickle")}
    cmd = [sys.executable, "-m", "avatar.cli", "dataset", "run", str(config_path), "-o", str(out)]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)  # fmt: skip
    deadline = time.time() + 240
    while time.time() < deadline and proc.poll() is None:
        manifest = out / "manifest.jsonl"
        if manifest.exists() and manifest.read_text().count("\n") >= 1:
            break
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)  # the command and its worker, mid-sample
    proc.wait()
    # resumed on two workers: each renders with its share of the cores (one Cycles thread
    # here), which must not change a label byte
    done = subprocess.run([*cmd, "--workers", "2"], capture_output=True, text=True,
                          timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    lines = (out / "manifest.jsonl").read_text().splitlines()
    assert sorted(json.loads(line)["id"] for line in lines) == [0, 1, 2]
    assert not list((out / "samples").glob(".tmp-*"))
    for i in range(3):
        for name in ("depth.exr", "normals.exr", "parts.png", "instances.png", "meta.json"):
            a = (clean / "samples" / f"{i:08d}" / name).read_bytes()
            b = (out / "samples" / f"{i:08d}" / name).read_bytes()
            assert a == b, (i, name)
    # the workers read the clean run's builds: nothing built or written again
    assert {p: p.stat().st_mtime_ns for p in cache.rglob("*.pickle")} == builds


def test_workers_share_the_cores_out_among_their_renders():
    from avatar.dataset import runner

    assert runner.render_threads(1, cores=2) == 0  # one worker: Cycles takes every core
    assert runner.render_threads(2, cores=2) == 1
    assert runner.render_threads(3, cores=8) == 2
    assert runner.render_threads(4, cores=2) == 1  # never zero threads


def _child_threads() -> dict:
    import os

    from pykdtree.kdtree import KDTree  # noqa: F401  (its OpenMP pool starts with the import)

    return {name: os.environ.get(name) for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")}


def test_spawned_workers_get_their_share_of_native_threads(monkeypatch):
    """Each worker's OpenMP (pykdtree) and OpenBLAS pools are limited as its Cycles is, in
    a real spawned process; the parent's environment is put back, a user's value kept."""
    import multiprocessing
    import os
    from concurrent.futures import ProcessPoolExecutor

    from avatar.dataset import runner

    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "3")  # the user's choice
    with runner.thread_limits(1):
        pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"))
        with pool:
            seen = pool.submit(_child_threads).result(timeout=120)
    assert seen == {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "3"}
    assert "OMP_NUM_THREADS" not in os.environ and os.environ["OPENBLAS_NUM_THREADS"] == "3"
    with runner.thread_limits(0):  # one worker: no limit
        assert "OMP_NUM_THREADS" not in os.environ


@pytest.mark.skipif(importlib.util.find_spec("ray") is None, reason="needs Ray (the ray extra)")
def test_ray_cluster_on_loopback_renders_the_same_samples(dataset, tmp_path):
    """A real local Ray cluster (`ray start --head` on 127.0.0.1): the same label bytes as
    the local engine."""
    import shutil

    _, clean = dataset
    ray_bin = Path(sys.executable).parent / "ray"
    env = dict(os.environ, RAY_ENABLE_UV_RUN_RUNTIME_ENV="0")
    start = subprocess.run([str(ray_bin), "start", "--head", "--node-ip-address=127.0.0.1",
                            "--port=0", "--num-cpus=1", "--include-dashboard=false",
                            "--disable-usage-stats"], capture_output=True, text=True, env=env,
                           timeout=180)  # fmt: skip
    if start.returncode != 0:
        pytest.skip(f"ray start failed here: {start.stderr[-300:]}")
    try:
        config_path = tmp_path / "ds.toml"
        config_path.write_text(CONFIG)
        out = tmp_path / "set"
        run = subprocess.run([sys.executable, "-m", "avatar.cli", "dataset", "run",
                              str(config_path), "-o", str(out), "-n", "2", "--engine", "ray"],
                             capture_output=True, text=True, timeout=600,
                             env=dict(env, RAY_ADDRESS="auto"))  # fmt: skip
        assert run.returncode == 0, run.stderr[-2000:]
    finally:
        subprocess.run([str(ray_bin), "stop", "--force"], capture_output=True, timeout=120)
    for i in range(2):
        for name in ("depth.exr", "parts.png", "instances.png"):
            assert (clean / "samples" / f"{i:08d}" / name).read_bytes() == \
                (out / "samples" / f"{i:08d}" / name).read_bytes(), (i, name)  # fmt: skip
    shutil.rmtree(out, ignore_errors=True)


def test_loader_returns_numpy_arrays(dataset):
    from avatar.dataset.loader import AvatarDataset

    c, out = dataset
    data = AvatarDataset(out)
    assert len(data) == 3
    s = data[1]
    h, w = 80, 96
    assert s["rgb"].shape == (h, w, 3) and s["rgb"].dtype == np.uint8
    assert s["depth"].shape == (h, w) and s["normals"].shape == (h, w, 3)
    assert s["instances"].dtype == np.uint16 and s["parts"].shape == (h, w)
    assert s["keypoints_2d"].shape[1:] == (17, 3) and s["K"].shape == (3, 3)
    lengths = np.linalg.norm(s["normals"][s["instances"] > 0], axis=-1)
    np.testing.assert_allclose(lengths, 1.0, atol=1e-3)
    with pytest.raises(IndexError):
        data[3]


def test_webdataset_shards_hold_every_sample_file(dataset, tmp_path):
    import tarfile

    from avatar.dataset import store

    _, out = dataset
    shards = store.write_shards(out, tmp_path / "shards", per_shard=2)
    assert [p.name for p in shards] == ["shard-000000.tar", "shard-000001.tar"]
    names = [m for p in shards for m in tarfile.open(p).getnames()]
    assert names[:6] == [f"00000000.{n}" for n in store.SAMPLE_FILES]
    assert len(names) == 3 * len(store.SAMPLE_FILES)
    again = store.write_shards(out, tmp_path / "again", per_shard=2)
    assert shards[0].read_bytes() == again[0].read_bytes()


def _rss_mb() -> float:
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) / 1024 for line in f if line.startswith("VmRSS:"))


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux /proc")
def test_a_worker_hands_freed_heap_pages_back_after_a_sample():
    """Freed buffers below a pinned one stay resident in glibc's heap (a long run's RSS
    creep); the worker's per-sample release hands them back."""
    from avatar.dataset import worker

    if worker._malloc_trim() is None:
        pytest.skip("not glibc")
    worker.release_freed_memory()
    blocks = [bytearray(64 * 1024) for _ in range(3000)]  # ~190 MB from the heap
    pinned = bytearray(64 * 1024)  # allocated last: the heap's top stays in use
    for block in blocks:
        block[::4096] = b"x" * len(block[::4096])  # touch every page
    before = _rss_mb()
    del blocks
    held = _rss_mb()
    worker.release_freed_memory()
    after = _rss_mb()
    assert held > before - 50  # freed, yet still resident
    assert after < held - 100, (before, held, after)
    del pinned


def _held_cores() -> tuple[int, tuple[int, ...]]:
    import os
    import time

    time.sleep(0.3)  # both workers alive at once
    return os.getpid(), tuple(sorted(os.sched_getaffinity(0)))


@pytest.mark.skipif(not hasattr(__import__("os"), "sched_setaffinity"), reason="Linux only")
def test_workers_are_held_to_disjoint_shares_of_the_cores():
    """Two real spawned workers (recycled after every task, as ``recycle_every`` does) each
    run on their own half of the cores, and a recycled worker takes the share left free."""
    import multiprocessing
    import os
    from concurrent.futures import ProcessPoolExecutor

    from avatar.dataset import runner

    cores = sorted(os.sched_getaffinity(0))
    if len(cores) < 2:
        pytest.skip("needs two cores")
    context = multiprocessing.get_context("spawn")
    slots = context.Array("i", 2)
    pool = ProcessPoolExecutor(2, mp_context=context, max_tasks_per_child=1,
                               initializer=runner.hold_to_share, initargs=(slots,))  # fmt: skip
    with pool:
        seen = [f.result(timeout=120) for f in [pool.submit(_held_cores) for _ in range(6)]]
    halves = {tuple(cores[0::2]), tuple(cores[1::2])}
    assert {held for _, held in seen} == halves  # each task on one half, both halves used
    assert len({pid for pid, _ in seen}) == 6  # every task in a new worker
