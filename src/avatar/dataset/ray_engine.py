"""The Ray engine: the same samples as the local engine, as Ray tasks on a cluster.

``ray.init()`` joins the cluster named by ``RAY_ADDRESS`` (e.g. after ``ray start --head``)
or starts a local one. Each task renders one sample exactly as a local worker does
(``runner._render_one``) into the shared output folder; a worker process is replaced after
``render.recycle_every`` tasks (``max_calls``), a task lost with its node is retried, and the
parent writes the manifest as results arrive, so a killed run resumes like a local one.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from avatar.dataset.config import Config
from avatar.errors import AvatarError


def render(config: Config, out: Path, todo: list[int], workers: int) -> Iterable[tuple]:
    """Yield (index, manifest entry or None, error or None) as Ray tasks finish."""
    try:
        import ray
    except ImportError:
        raise AvatarError("--engine ray needs Ray: pip install 'avatar[ray]'") from None
    from avatar.dataset.runner import _render_one

    started = not ray.is_initialized()
    if started:
        address = os.environ.get("RAY_ADDRESS")
        ray.init(address=address, num_cpus=None if address else max(1, workers),
                 include_dashboard=False, log_to_driver=False)  # fmt: skip
    task = ray.remote(num_cpus=1, max_retries=3, max_calls=config.render.recycle_every)(
        _render_one
    )
    try:
        # a task holds one CPU of its node: one Cycles thread, so a node's tasks share its cores
        pending = {task.remote(config, i, str(out), 1): i for i in todo}
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                index = pending.pop(ref)
                try:
                    yield ray.get(ref)
                except Exception as exc:  # noqa: BLE001 - a task that failed for good
                    yield index, None, f"ray task failed: {exc.__class__.__name__}: {exc}"
    finally:
        if started:
            ray.shutdown()
