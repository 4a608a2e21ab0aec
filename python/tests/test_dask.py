"""sightline.dask.build on a LocalCluster: byte-identical to one build, and a worker
killed mid-shard is retried and resumes from its journal."""

import os
from pathlib import Path

import pytest

distributed = pytest.importorskip("distributed")
import cloudpickle  # noqa: E402

import sightline  # noqa: E402
import sightline.dask  # noqa: E402

# The workers unpickle the kill hook below: ship this module by value.
cloudpickle.register_pickle_by_value(__import__(__name__))


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
    )
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


class KillOnce:
    """Kill the worker process running shard 0 once its journal holds `after` cells."""

    def __init__(self, marker: str, after: int):
        self.marker = marker
        self.after = after

    def __call__(self, shard: int, done: int, total: int) -> None:
        if shard == 0 and done >= self.after and not os.path.exists(self.marker):
            Path(self.marker).write_text(str(done))
            os._exit(1)


def test_dask_build_is_byte_identical_to_one_build(client, scene, scene_path, tmp_path):
    cells = scene.cells(size=10)
    single = tmp_path / "single.pvs"
    sightline.build(scene, cells, "dual-ray", single)
    out = tmp_path / "dask.pvs"
    result = sightline.dask.build(scene_path, cells, "dual-ray", out, client, shards=3)
    assert out.read_bytes() == single.read_bytes()
    assert result["cells"] == len(cells) and len(result["shards"]) == 3
    assert result["computed"] == len(cells) and result["resumed"] == 0
    assert not sightline.dask.shard_dir(out).exists()


def test_killed_worker_resumes_its_shard(client, scene, scene_path, tmp_path):
    cells = scene.cells(size=10)
    single = tmp_path / "single.pvs"
    sightline.build(scene, cells, "erosion", single)
    marker = tmp_path / "killed"
    out = tmp_path / "dask.pvs"
    result = sightline.dask.build(
        scene_path, cells, "erosion", out, client, shards=2, progress=KillOnce(str(marker), after=4)
    )
    assert marker.exists(), "the worker was never killed"
    killed_at = int(marker.read_text())
    assert out.read_bytes() == single.read_bytes()
    shard0 = next(s for s in result["shards"] if s["shard"] == "0/2")
    # Every cell finished before the kill came from the journal; the rest were computed.
    assert shard0["resumed"] == killed_at
    assert shard0["computed"] == shard0["cells"] - killed_at
    assert result["computed"] + result["resumed"] == len(cells)


def test_dask_build_bad_input(client, scene_path, tmp_path):
    with pytest.raises(sightline.MethodError):
        sightline.dask.build(scene_path, [[0, 0, 1, 1, 1, 2]], "nope", tmp_path / "x.pvs", client)
    with pytest.raises(sightline.SceneError):
        sightline.dask.build(tmp_path / "none.geojson", [[0, 0, 1, 1, 1, 2]], "all", tmp_path / "x.pvs", client)
    # Other keywords are method knobs by key: an unknown one names the method's knobs.
    with pytest.raises(sightline.MethodError, match="colour"):
        sightline.dask.build(scene_path, [[0, 0, 1, 1, 1, 2]], "all", tmp_path / "x.pvs", client, colour=1)
