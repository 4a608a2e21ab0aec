"""Gameplay queries of a .pvs (can_see, seen_by, secondary), each checked against the
sets it derives from: on a city file two cells may see each other when their sets share
an object (docs/engines.md states the guarantee)."""

import numpy as np
import pytest

import sightline
from sightline import CellError


@pytest.fixture(scope="module")
def city_pvs(scene, tmp_path_factory):
    cells = scene.cells(size=10)
    out = tmp_path_factory.mktemp("gameplay") / "city.pvs"
    sightline.build(scene, cells, "erosion", out, threads=2)
    f = sightline.PvsFile.open(out)
    sets = [set(f.pvs(i).tolist()) for i in range(len(f))]
    return f, sets


def test_can_see_is_a_shared_object(city_pvs):
    f, sets = city_pvs
    n = len(f)
    for a in range(n):
        for b in range(n):
            assert f.can_see(a, b) == (a == b or bool(sets[a] & sets[b])), (a, b)
    with pytest.raises(CellError, match="out of range"):
        f.can_see(0, n)


def test_seen_by_lists_the_cells_seeing_the_point(city_pvs):
    f, sets = city_pvs
    for i, c in enumerate(f.cells):
        x, y = (c[0] + c[3]) / 2, (c[1] + c[4]) / 2
        seen = f.seen_by(x, y, 1.7)
        cell = f.locate(x, y, 1.7)
        expected = [a for a in range(len(f)) if a == cell or sets[a] & sets[cell]]
        assert seen.dtype == np.uint32 and seen.tolist() == expected, i
    assert f.seen_by(-1e6, 0, 1.7) is None


def test_secondary_is_the_union_of_the_sets_seeing_the_cell(city_pvs):
    f, sets = city_pvs
    for a in range(len(f)):
        seeing = [b for b in range(len(f)) if b == a or sets[a] & sets[b]]
        union = sorted(set().union(*(sets[b] for b in seeing)))
        got = f.secondary(a)
        assert got.dtype == np.uint32 and got.tolist() == union
        assert sets[a] <= set(got.tolist())
