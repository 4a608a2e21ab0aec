"""Quake levels (``.bsp``) from Python: the same calls as for a city, with the portal
methods, answering as ``sightline pvs LEVEL.bsp --at`` and ``info`` do."""

from pathlib import Path

import numpy as np
import pytest

import sightline
from sightline import CellError, MethodError

LEVELS = Path(__file__).resolve().parents[2] / "data" / "quake"
# A point of dm1's open space (README: leaf 191).
DM1_POINT = [200.0, 1000.0, 50.0]


@pytest.fixture(scope="module")
def dm1():
    return sightline.Scene.from_file(LEVELS / "dm1.bsp")


def test_e1m1_loads_with_its_leaves_and_portals():
    level = sightline.Scene.from_file(LEVELS / "e1m1.bsp")
    info = level.info()
    assert info["objects"] == len(level) > 0
    # Golden facts of the shared data README.
    assert info["bsp"]["visleafs"] == 1206
    assert info["bsp"]["portals"] > 1206
    assert info["bsp"]["open_leaves"] <= info["bsp"]["visleafs"] < info["bsp"]["leaves"]


def test_pvs_at_a_point_fast_contains_full(dm1):
    fast = dm1.pvs_at(DM1_POINT, method="portals-fast")
    full = dm1.pvs_at(DM1_POINT, method="portals")
    for r in (fast, full):
        assert r["leaf"] == 191
        assert r["leaf"] in r["visible_leaves"]
        for key in ("visible", "visible_leaves"):
            assert r[key].dtype == np.uint32
            assert np.all(np.diff(r[key].astype(np.int64)) > 0)
        assert r["visible"].max() < len(dm1)
    assert set(full["visible"]) <= set(fast["visible"])
    assert set(full["visible_leaves"]) <= set(fast["visible_leaves"])
    assert len(full["visible_leaves"]) < len(fast["visible_leaves"])


def test_pvs_of_a_cell_is_the_union_of_its_leaves(dm1):
    x, y, z = DM1_POINT
    box = [x - 1, y - 1, z - 1, x + 1, y + 1, z + 1]
    cell = dm1.pvs(box, method="portals-fast")
    at = dm1.pvs_at(DM1_POINT, method="portals-fast")
    assert set(at["visible"]) <= set(cell)
    many = dm1.pvs_many([box, box], method="portals-fast")
    assert all(np.array_equal(m, cell) for m in many)


def test_bad_points_and_methods_raise(dm1, scene, street_cell):
    with pytest.raises(CellError, match="not in open space"):
        dm1.pvs_at([1e5, 1e5, 1e5], method="portals-fast")
    with pytest.raises(CellError):
        dm1.pvs_at([1.0, 2.0], method="portals-fast")
    with pytest.raises(MethodError, match="portal method"):
        dm1.pvs_at(DM1_POINT, method="erosion")
    # The portal methods need a level's tree.
    with pytest.raises(MethodError, match="BSP levels"):
        scene.pvs(street_cell, method="portals")
    with pytest.raises(MethodError, match="BSP levels"):
        scene.pvs_at([0, 0, 0], method="portals-fast")
