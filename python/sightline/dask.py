"""A distributed ``build`` on a Dask cluster.

:func:`build` splits the cells into ``N`` interleaved shards (cell ``k`` belongs to shard
``k mod N``, the ``--shard I/N`` rule of the command line), runs one task per shard on the
cluster's workers — each writes its shard file, with its journal, into a directory shared
by the workers and the client — and merges the shards into ``out``. The merged file is
byte-identical to a single :func:`sightline.build` of all cells.

A task whose worker dies (killed, out of memory, preempted) is rescheduled by Dask; the
retried task resumes its shard from the journal and recomputes no finished cell. A task
that raises is retried ``retries`` times.

>>> from dask.distributed import Client, LocalCluster              # doctest: +SKIP
>>> client = Client(LocalCluster(n_workers=2, threads_per_worker=1))  # doctest: +SKIP
>>> sightline.dask.build("city.geojson", "cells.json", "dual-ray",
...                      "city.pvs", client)                        # doctest: +SKIP
"""

from __future__ import annotations

import os
import shutil
import threading
import uuid
from pathlib import Path
from typing import Any, Callable, Dict, Optional, Tuple

import sightline

__all__ = ["build", "shard_dir"]

_SCENES: Dict[Tuple[str, int, int, Optional[str]], "sightline.Scene"] = {}
_SCENES_LOCK = threading.Lock()


def shard_dir(out: "os.PathLike[str] | str") -> Path:
    """The directory next to ``out`` that holds the shard files and their journals."""
    out = Path(out)
    return out.with_name(out.name + ".shards")


def _shard_path(directory: Path, index: int, count: int) -> Path:
    return directory / f"shard-{index:05d}-of-{count:05d}.pvs"


def _scene(path: str, crs: Optional[str]) -> "sightline.Scene":
    """The scene of ``path``, loaded once per worker process (and reloaded if the file changes)."""
    st = os.stat(path)
    key = (os.path.abspath(path), st.st_mtime_ns, st.st_size, crs)
    with _SCENES_LOCK:
        scene = _SCENES.get(key)
        if scene is None:
            scene = sightline.Scene.from_file(path, crs=crs)
            _SCENES.clear()
            _SCENES[key] = scene
        return scene


def _worker_threads() -> Optional[int]:
    try:
        from distributed import get_worker

        return get_worker().state.nthreads
    except (ImportError, ValueError, AttributeError):
        return None


def _build_shard(
    scene_path: str,
    crs: Optional[str],
    cells_path: str,
    method: str,
    out: str,
    index: int,
    count: int,
    options: Dict[str, Any],
    threads: Optional[int],
    progress: Optional[Callable[[int, int, int], None]],
) -> Dict[str, Any]:
    """One shard, on a worker: resume it from its journal if a previous try left one."""
    if os.path.exists(out):
        # A retry of a task whose shard was already written: nothing left to do.
        stored = len(sightline.PvsFile.open(out).stored())
        return {"shard": f"{index}/{count}", "out": out, "cells": stored, "resumed": stored, "computed": 0}
    report = None
    if progress is not None:

        def report(done: int, total: int) -> None:
            progress(index, done, total)

    stats = sightline.build(
        _scene(scene_path, crs),
        cells_path,
        method,
        out,
        resume=True,
        shard=(index, count),
        threads=threads if threads is not None else _worker_threads(),
        progress=report,
        **options,
    )
    return stats


def build(
    scene_path: "os.PathLike[str] | str",
    cells: Any,
    method: str,
    out: "os.PathLike[str] | str",
    client: Any,
    shards: Optional[int] = None,
    retries: int = 3,
    crs: Optional[str] = None,
    threads: Optional[int] = None,
    progress: Optional[Callable[[int, int, int], None]] = None,
    keep_shards: bool = False,
    **opts: Any,
) -> Dict[str, Any]:
    """Build the ``.pvs`` of ``cells`` on the workers of the Dask ``client`` and merge it
    into ``out``.

    ``scene_path`` and the directory of ``out`` must be reachable under the same paths
    from every worker (a shared file system). ``cells`` is an N×6 array or a cells.json
    path; ``shards`` defaults to four per worker thread (at most one per cell); ``opts``
    are the method options of :func:`sightline.build` (``resolution``, ``sweep``,
    ``planes``, and any other knob of :func:`sightline.methods` by key). ``threads`` is the number of threads of each task (the worker's thread
    count when ``None``); ``progress(shard, done, total)`` is called on the workers.
    The shard files, their journals and the cells live in :func:`shard_dir` ``(out)``,
    removed after a successful merge unless ``keep_shards``. Returns the merge result and
    the statistics of every shard (``resumed`` counts the cells a retried task took
    from its journal).
    """
    common = ("resolution", "sweep", "planes")
    knobs = {k: v for k, v in opts.items() if k not in common}
    scene_path = os.path.abspath(os.fspath(scene_path))
    if not os.path.exists(scene_path):
        raise sightline.SceneError(f"cannot load {scene_path}: no such file")
    cells_array = sightline.read_cells(cells) if isinstance(cells, (str, os.PathLike)) else cells
    cells_bytes = sightline._cells_bytes(cells_array)
    n_cells = len(cells_bytes) // 48
    if n_cells == 0:
        raise sightline.CellError("no cells to build")
    if shards is None:
        workers = sum(client.nthreads().values()) or 1
        shards = 4 * workers
    shards = int(shards)
    if shards < 1:
        raise sightline.PvsFileError(f"shards must be at least 1, got {shards}")
    shards = min(shards, n_cells)
    # Fail on the client, not on every worker, for a bad method or options.
    sightline._native.check_method(
        method,
        opts.get("resolution"),
        bool(opts.get("sweep", False)),
        opts.get("planes"),
        sightline._knobs(knobs),
    )

    out = Path(os.path.abspath(os.fspath(out)))
    directory = shard_dir(out)
    directory.mkdir(parents=True, exist_ok=True)
    cells_path = directory / "cells.json"
    sightline.write_cells(cells_array, cells_path)
    token = uuid.uuid4().hex[:8]
    futures = [
        client.submit(
            _build_shard,
            scene_path,
            crs,
            str(cells_path),
            method,
            str(_shard_path(directory, i, shards)),
            i,
            shards,
            dict(opts),
            threads,
            progress,
            key=f"sightline-shard-{i}-of-{shards}-{token}",
            pure=False,
            retries=retries,
        )
        for i in range(shards)
    ]
    stats = client.gather(futures)
    merged = sightline.merge([_shard_path(directory, i, shards) for i in range(shards)], out)
    if not keep_shards:
        shutil.rmtree(directory, ignore_errors=True)
    merged["shards"] = stats
    merged["resumed"] = sum(s["resumed"] for s in stats)
    merged["computed"] = sum(s["computed"] for s in stats)
    return merged
