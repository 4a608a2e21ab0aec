"""Unit tests of the Python API: every function, and bad input raising, not crashing."""

import json

import numpy as np
import pytest

import sightline
from sightline import CellError, MethodError, PvsFileError, SceneError, SightlineError

from conftest import BLOCK, N, STREET, X0, Y0


def test_exception_hierarchy():
    for cls in (SceneError, CellError, MethodError, PvsFileError):
        assert issubclass(cls, SightlineError)
    assert issubclass(SightlineError, ValueError)


def test_info_matches_the_cli_report(scene, scene_path):
    info = scene.info()
    assert info["scene"] == str(scene_path)
    assert info["objects"] == len(scene) == N * N
    assert info["blocks"] == N * N and info["flat"] == 0 and info["meshes"] == 0
    # A box prism: 4 walls × 2 triangles + 2 cap triangles.
    assert info["triangles"] == N * N * 10
    assert info["bounds"][:2] == [X0, Y0]
    assert info["fingerprint"] == scene.fingerprint
    assert info["warnings"] == []


def test_cells_are_a_float_grid_outside_the_blocks(scene):
    cells = scene.cells(size=10, z=(1.5, 2.0))
    assert cells.dtype == np.float64 and cells.ndim == 2 and cells.shape[1] == 6
    # 11×11 grid of 10 m cells (the last column/row ends at the bounds), minus 4 per block.
    assert len(cells) == 11 * 11 - 4 * N * N
    assert np.all(cells[:, 2] == 1.5) and np.all(cells[:, 5] == 2.0)


@pytest.mark.parametrize("size, z", [(0, (1.5, 2)), (float("nan"), (1.5, 2)), (10, (2, 1)), (10, (-1, 2)), (10, "ab")])
def test_bad_cell_grid_raises(scene, size, z):
    with pytest.raises(CellError):
        scene.cells(size=size, z=z)


def test_pvs_of_one_cell(scene, street_cell):
    ids = scene.pvs(street_cell, method="dual-ray")
    assert ids.dtype == np.uint32
    assert np.all(np.diff(ids.astype(np.int64)) > 0)
    # The two blocks on either side of the street are visible.
    assert {0, 1} <= set(ids.tolist())
    text = ",".join(str(v) for v in street_cell)
    assert np.array_equal(scene.pvs(text, method="dual-ray"), ids)
    assert np.array_equal(scene.pvs(street_cell, method="all"), np.arange(N * N, dtype=np.uint32))


def test_pvs_contains_the_ground_truth(scene, street_cell):
    truth = scene.truth(street_cell, samples=16, resolution=128)
    assert truth["samples_used"] > 0
    vis = set(truth["visible"].tolist())
    assert vis <= set(scene.pvs(street_cell, method="dual-ray").tolist())
    assert vis <= set(scene.pvs(street_cell, method="erosion").tolist())


def test_pvs_many_equals_pvs_one_by_one(scene):
    cells = scene.cells(size=10)[:12]
    many = scene.pvs_many(cells, method="dual-ray", threads=2)
    assert len(many) == len(cells)
    for c, ids in zip(cells, many):
        assert np.array_equal(ids, scene.pvs(c, method="dual-ray"))
    assert all(np.array_equal(a, b) for a, b in zip(many, scene.pvs_many(cells, "dual-ray", threads=1)))


@pytest.mark.parametrize(
    "cell",
    ["1,2,3", "a,b,c,d,e,f", [0, 0, 0, 1, 1], [0, 0, 2, 1, 1, 1], [0, 0, float("nan"), 1, 1, 2], None, "[1,2]"],
)
def test_bad_cells_raise(scene, cell):
    with pytest.raises(CellError):
        scene.pvs(cell)


def test_bad_cells_in_many_raise(scene):
    with pytest.raises(CellError):
        scene.pvs_many(np.zeros((3, 5)))
    with pytest.raises(CellError, match="cell 1"):
        scene.pvs_many([[0, 0, 1, 1, 1, 2], [0, 0, 3, 1, 1, 2]])


def test_bad_method_and_options_raise(scene, street_cell):
    with pytest.raises(MethodError, match="unknown method 'nope'"):
        scene.pvs(street_cell, method="nope")
    with pytest.raises(MethodError, match="ext-proj"):
        scene.pvs(street_cell, method="erosion", sweep=True)
    with pytest.raises(MethodError, match="threads"):
        scene.pvs_many([street_cell], threads=0)
    with pytest.raises(MethodError, match="samples"):
        scene.truth(street_cell, samples=0)


def test_registry_and_knobs_by_key(scene, street_cell, tmp_path):
    ms = {m["name"]: m for m in sightline.methods()}
    assert set(ms) == set(sightline.METHOD_NAMES)
    assert not ms["sampled"]["conservative"] and ms["dual-ray"]["conservative"]
    keys = {k["key"] for k in ms["dual-ray"]["knobs"]}
    assert {"resolution", "virtual_occluders", "hidden_boxes"} <= keys
    base = set(scene.pvs(street_cell, method="dual-ray").tolist())
    tighter = set(scene.pvs(street_cell, method="dual-ray", virtual_occluders=True).tolist())
    truth = set(scene.truth(street_cell, samples=16, resolution=128)["visible"].tolist())
    # Virtual occluders can only remove hidden objects.
    assert truth <= tighter <= base
    with pytest.raises(MethodError, match="unknown option 'nope'"):
        scene.pvs(street_cell, method="dual-ray", nope=1)
    with pytest.raises(MethodError, match="hidden_boxes"):
        scene.pvs(street_cell, method="dual-ray", hidden_boxes="maybe")
    out = tmp_path / "vo.pvs"
    sightline.build(scene, scene.cells(size=10)[:4], "dual-ray", out, virtual_occluders=True)
    params = sightline.PvsFile.open(out).params
    assert params.get("virtual_occluders") == "true"


def test_truth_of_a_cell_inside_a_block_raises(scene):
    with pytest.raises(CellError, match="no free space"):
        scene.truth([X0 + 5, Y0 + 5, 1.5, X0 + 10, Y0 + 10, 2.0], samples=8, resolution=64)


def test_build_query_and_check(scene, tmp_path):
    cells = scene.cells(size=10)
    out = tmp_path / "city.pvs"
    seen = []
    stats = sightline.build(scene, cells, "dual-ray", out, threads=2, progress=lambda d, t: seen.append((d, t)))
    assert stats["cells"] == len(cells) and stats["computed"] == len(cells) and stats["resumed"] == 0
    assert seen[-1] == (len(cells), len(cells))
    assert not (tmp_path / "city.pvs.journal").exists()
    f = sightline.PvsFile.open(out)
    assert len(f) == len(cells) and f.method == "dual-ray" and f.object_count == N * N
    assert f.fingerprint == scene.fingerprint and f.shard is None
    assert np.array_equal(f.cells, cells)
    c = cells[7]
    q = f.query((c[0] + c[3]) / 2, (c[1] + c[4]) / 2, 1.7)
    assert q.index == 7 and np.array_equal(q.cell, c)
    assert np.array_equal(q.visible, scene.pvs(c, "dual-ray"))
    assert f.locate(0, 0, 0) is None
    with pytest.raises(CellError, match="no cell"):
        f.query(0, 0, 0)
    f.verify()
    report = sightline.check(scene, out, cells=3)
    assert report["cells"] == 3 and report["missed"] == 0 and report["method"] == "dual-ray"
    report = sightline.check(scene, method="erosion", cells=cells[:2], strict=True)
    assert report["cells"] == 2 and report["missed"] == 0 and report["conservative"]


def test_build_refuses_a_stale_journal_and_resumes_it(scene, tmp_path):
    cells = scene.cells(size=10)[:6]
    out = tmp_path / "a.pvs"
    sightline.build(scene, cells, "erosion", out)
    reference = out.read_bytes()
    out.unlink()
    # A journal left next to the output is never overwritten silently.
    (tmp_path / "a.pvs.journal").write_bytes(b"")
    with pytest.raises(PvsFileError, match="resume=True"):
        sightline.build(scene, cells, "erosion", out)
    with pytest.raises(PvsFileError, match="journal"):
        sightline.build(scene, cells, "erosion", out, resume=True)
    (tmp_path / "a.pvs.journal").unlink()
    shard0 = tmp_path / "s0.pvs"
    shard1 = tmp_path / "s1.pvs"
    assert sightline.build(scene, cells, "erosion", shard0, shard=(0, 2))["cells"] == 3
    assert sightline.build(scene_path_of(scene), cells, "erosion", shard1, shard="1/2")["cells"] == 3
    assert sightline.PvsFile.open(shard0).shard == "0/2"
    with pytest.raises(PvsFileError, match="missing"):
        sightline.merge([shard0], tmp_path / "m.pvs")
    sightline.merge([shard1, shard0], tmp_path / "m.pvs")
    assert (tmp_path / "m.pvs").read_bytes() == reference


def scene_path_of(scene):
    return scene.info()["scene"]


def test_cells_json_round_trip(scene, tmp_path):
    cells = scene.cells(size=10)
    sightline.write_cells(cells, tmp_path / "cells.json")
    assert np.array_equal(sightline.read_cells(tmp_path / "cells.json"), cells)
    assert json.loads((tmp_path / "cells.json").read_text())[0] == cells[0].tolist()
    (tmp_path / "bad.json").write_text("{}")
    with pytest.raises(CellError, match="JSON array"):
        sightline.read_cells(tmp_path / "bad.json")


def test_corrupted_pvs_raises(scene, tmp_path):
    cells = scene.cells(size=10)[:4]
    out = tmp_path / "c.pvs"
    sightline.build(scene, cells, "all", out)
    data = bytearray(out.read_bytes())
    (tmp_path / "trunc.pvs").write_bytes(bytes(data[: len(data) // 2]))
    with pytest.raises(PvsFileError):
        sightline.PvsFile.open(tmp_path / "trunc.pvs")
    (tmp_path / "junk.pvs").write_bytes(b"not a pvs at all")
    with pytest.raises(PvsFileError, match="bad magic"):
        sightline.PvsFile.open(tmp_path / "junk.pvs")
    data[-10] ^= 0xFF
    (tmp_path / "flip.pvs").write_bytes(bytes(data))
    with pytest.raises(PvsFileError):
        f = sightline.PvsFile.open(tmp_path / "flip.pvs")
        f.verify()
    with pytest.raises(PvsFileError, match="cannot open"):
        sightline.PvsFile.open(tmp_path / "missing.pvs")


def test_bad_scene_files_raise(tmp_path):
    with pytest.raises(SceneError, match="cannot load"):
        sightline.Scene.from_file(tmp_path / "missing.geojson")
    (tmp_path / "broken.geojson").write_text("{not json")
    with pytest.raises(SceneError, match="invalid JSON"):
        sightline.Scene.from_file(tmp_path / "broken.geojson")
    with pytest.raises(SceneError, match="unsupported input format"):
        sightline.Scene.from_file(tmp_path / "x.txt")
    with pytest.raises(SceneError, match="crs"):
        sightline.Scene.from_file(tmp_path / "broken.geojson", crs="mercator")


def test_build_bad_input(scene, tmp_path):
    with pytest.raises(CellError):
        sightline.build(scene, np.zeros((0, 6)), "all", tmp_path / "e.pvs")
    with pytest.raises(PvsFileError, match="shard"):
        sightline.build(scene, scene.cells(10)[:2], "all", tmp_path / "e.pvs", shard="3/2")
    assert not (tmp_path / "e.pvs").exists()


def test_visible_from_culls_conservatively(scene):
    # From the street between the first two rows of blocks, looking along it (+x).
    eye = [X0 - 5.0, Y0 + BLOCK + STREET / 2.0, 1.7]
    for method in ("hzb", "hom", "cplp"):
        ids = scene.visible_from(eye, [1.0, 0.0, 0.0], fov_deg=60, width=320, height=180, method=method)
        assert ids.dtype == np.uint32
        assert list(ids) == sorted(set(ids))
        assert 0 < len(ids) < len(scene)
    with pytest.raises(MethodError):
        scene.visible_from(eye, [1, 0, 0], method="zbuffer")
    with pytest.raises(CellError):
        scene.visible_from(eye, [0, 0, 0])
    with pytest.raises(CellError):
        scene.visible_from([float("nan"), 0, 0], [1, 0, 0])
