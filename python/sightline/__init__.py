"""Conservative potentially visible sets (PVS) for cities, from Python.

The package wraps the sightline engine (Rust): the importers, the viewcell grid, the
visibility methods, the ground truth and the ``.pvs`` store. Nothing is re-implemented
here: every rule, default and error message is the command line's.

>>> import sightline
>>> scene = sightline.Scene.from_file("data/lyon1_bdtopo.geojson")  # doctest: +SKIP
>>> cells = scene.cells(size=25)                                     # doctest: +SKIP
>>> visible = scene.pvs(cells[0], method="dual-ray")                 # doctest: +SKIP
>>> sightline.build(scene, cells, "dual-ray", "lyon.pvs")            # doctest: +SKIP
>>> sightline.PvsFile.open("lyon.pvs").query(*cells[0][:3])          # doctest: +SKIP

Errors are :class:`SightlineError` (a :class:`ValueError`) or one of its subclasses,
carrying the command line's one-line message.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import (
    CellError,
    MethodError,
    PvsFileError,
    SceneError,
    SightlineError,
)

__all__ = [
    "METHOD_NAMES",
    "CellError",
    "MethodError",
    "PvsFile",
    "PvsFileError",
    "PvsQuery",
    "Scene",
    "SceneError",
    "SightlineError",
    "build",
    "check",
    "merge",
    "methods",
    "read_cells",
    "write_cells",
]

#: Every method name, in the order of the specification.
METHOD_NAMES: Tuple[str, ...] = tuple(_native.METHOD_NAMES)



def methods() -> list:
    """The registry: every method with its ``family``, ``paper``, ``summary``, whether
    it is ``conservative`` and its ``knobs`` (keys accepted as keyword arguments by
    :meth:`Scene.pvs`, :func:`build` and :func:`check`, as ``--set key=value``).

    >>> [m["name"] for m in sightline.methods()][:2]  # doctest: +SKIP
    ['erosion', 'erosion-segment']
    """
    return json.loads(_native.methods_json())


def _knobs(knobs: dict) -> list:
    """Method knobs as ``(key, value)`` text pairs (``True`` → ``"true"``)."""
    out = []
    for k, v in knobs.items():
        if isinstance(v, bool):
            v = "true" if v else "false"
        out.append((str(k), str(v)))
    return out


PathLike = Union[str, "os.PathLike[str]"]
CellLike = Union[str, Sequence[float], np.ndarray]
CellsLike = Union[np.ndarray, Sequence[Sequence[float]], PathLike]


def _cell(cell: CellLike) -> list:
    """Six floats from a sequence or an ``"x0,y0,z0,x1,y1,z1"`` string."""
    if isinstance(cell, str):
        return list(_native.parse_cell(cell))
    try:
        values = [float(v) for v in np.asarray(cell, dtype=np.float64).reshape(-1)]
    except (TypeError, ValueError) as e:
        raise CellError(f"a viewcell is 6 numbers x0,y0,z0,x1,y1,z1, got {cell!r}") from e
    if len(values) != 6:
        raise CellError(f"a viewcell is 6 numbers x0,y0,z0,x1,y1,z1, got {len(values)}")
    return values


def _cells_bytes(cells: CellsLike) -> bytes:
    """The little-endian bytes of an N×6 float64 array (a cells.json path is read)."""
    if isinstance(cells, (str, os.PathLike)):
        return bytes(_native.read_cells(os.fspath(cells)))
    try:
        a = np.asarray(cells, dtype="<f8")
    except (TypeError, ValueError) as e:
        raise CellError("cells must be an N×6 array of numbers") from e
    if a.ndim == 1 and a.size == 6:
        a = a.reshape(1, 6)
    if a.ndim != 2 or a.shape[1] != 6:
        raise CellError(f"cells must be an N×6 array of numbers, got shape {a.shape}")
    return np.ascontiguousarray(a).tobytes()


def _cells_array(raw: bytes) -> np.ndarray:
    return np.frombuffer(raw, dtype="<f8").reshape(-1, 6).astype(np.float64)


def _ids(raw: bytes) -> np.ndarray:
    return np.frombuffer(raw, dtype="<u4").astype(np.uint32)


def read_cells(path: PathLike) -> np.ndarray:
    """Read a ``cells.json`` (a JSON array of ``[x0,y0,z0,x1,y1,z1]``) as an N×6 array.

    >>> sightline.read_cells("cells.json").shape  # doctest: +SKIP
    (1325, 6)
    """
    return _cells_array(_native.read_cells(os.fspath(path)))


def write_cells(cells: CellsLike, path: PathLike) -> None:
    """Write cells as a ``cells.json`` readable by ``sightline build --cells``, atomically."""
    text = _native.cells_json(_cells_bytes(cells))
    path = Path(path)
    tmp = path.with_name(path.name + f".tmp{os.getpid()}")
    tmp.write_text(text)
    os.replace(tmp, path)


class Scene:
    """A scene: objects (ids = input order), bounds and import warnings. A Quake level
    (``.bsp``) loads its world faces as the objects (id = face index) and keeps its BSP
    tree for the portal methods (``"portals"``, ``"portals-fast"``).

    Prepared methods are cached on the scene per (method, options), so repeated
    :meth:`pvs` calls prepare nothing twice.

    >>> scene = sightline.Scene.from_file("data/lyon1_bdtopo.geojson")  # doctest: +SKIP
    >>> len(scene), scene.info()["warning_counts"]                      # doctest: +SKIP
    """

    def __init__(self, native: "_native.NativeScene") -> None:
        self._native = native

    @classmethod
    def from_file(cls, path: PathLike, crs: str | None = None, strict: bool = False) -> "Scene":
        """Load a scene file; the format comes from the extension, as ``sightline``.

        ``crs`` is ``None``/``"auto"`` (detect WGS84 lon/lat), ``"projected"`` or
        ``"wgs84"``. A feature that cannot be used is skipped with a counted
        ``skipped-feature`` warning (see ``info()["warnings"]``); ``strict=True`` raises
        on the first one instead, as ``sightline --strict``.

        >>> sightline.Scene.from_file("city.geojson", crs="projected")  # doctest: +SKIP
        """
        return cls(_native.NativeScene.load(os.fspath(path), crs, strict))

    @classmethod
    def from_geojson(
        cls,
        geojson: Union[str, dict],
        crs: str | None = None,
        name: str = "<geojson>",
        strict: bool = False,
    ) -> "Scene":
        """Import GeoJSON text or a GeoJSON dict with the ``.geojson`` importer's rules."""
        text = geojson if isinstance(geojson, str) else json.dumps(geojson, allow_nan=False)
        return cls(_native.NativeScene.from_geojson(text, name, crs, strict))

    @classmethod
    def from_geodataframe(
        cls,
        gdf: Any,
        height: str = "height",
        min_height: str | None = None,
        name: str | None = None,
        strict: bool = False,
    ) -> "Scene":
        """Import a GeoPandas GeoDataFrame of Polygon/MultiPolygon buildings.

        ``height`` names the column of top heights (metres above the ground; 0 makes a
        flat object), ``min_height`` the optional column of base heights, ``name`` an
        optional column of object names. Row ``k`` becomes feature ``k`` (warnings name
        it). The CRS may be any projected CRS in metres, or a geographic one (reprojected
        to WGS84 lon/lat, then projected as the CLI does). Without a CRS, or with
        EPSG:4326 (which GeoPandas reports for every GeoJSON file), lon/lat is detected
        from the coordinates as the CLI does. Every validation and repair rule is the GeoJSON
        importer's: a row the importer cannot use (a negative height, a base above its
        top) is skipped with a counted ``skipped-feature`` warning naming it, or raises
        with ``strict=True``; missing columns, non-numeric or NaN heights and geometries
        that are not polygons always raise.

        >>> import geopandas as gpd                                          # doctest: +SKIP
        >>> gdf = gpd.read_file("data/lyon1_bdtopo.geojson")                 # doctest: +SKIP
        >>> scene = sightline.Scene.from_geodataframe(gdf, height="height")  # doctest: +SKIP
        """
        from ._geo import geodataframe_to_geojson

        text, crs = geodataframe_to_geojson(gdf, height, min_height, name)
        return cls(_native.NativeScene.from_geojson(text, "<GeoDataFrame>", crs, strict))

    def __len__(self) -> int:
        return len(self._native)

    def __repr__(self) -> str:
        return f"<sightline.Scene {self._native.source}: {len(self)} objects>"

    @property
    def fingerprint(self) -> str:
        """The geometry's 64-bit fingerprint (hex), stored in every ``.pvs`` built from it."""
        return self._native.fingerprint

    def info(self) -> dict:
        """Counts, bounds, fingerprint and warnings: the ``sightline info --json`` report.

        >>> scene.info()["objects"]  # doctest: +SKIP
        1523
        """
        return json.loads(self._native.info_json())

    def cells(self, size: float = 50.0, z: Tuple[float, float] = (1.5, 2.0)) -> np.ndarray:
        """The viewcell grid of ``sightline cells``: square cells of side ``size`` (m) at eye
        heights ``z = (z0, z1)``, keeping those with free space. An N×6 float64 array
        ``[x0, y0, z0, x1, y1, z1]``.

        >>> scene.cells(size=25).shape  # doctest: +SKIP
        (1325, 6)
        """
        try:
            z0, z1 = (float(v) for v in z)
        except (TypeError, ValueError) as e:
            raise CellError(f"z must be a pair (z0, z1) of numbers, got {z!r}") from e
        return _cells_array(self._native.cells(float(size), z0, z1))

    def pvs(
        self,
        cell: CellLike,
        method: str = "dual-ray",
        resolution: int | None = None,
        sweep: bool = False,
        planes: int | None = None,
        **knobs: Any,
    ) -> np.ndarray:
        """The potentially visible set of one viewcell: sorted object ids (uint32).

        ``cell`` is 6 numbers or an ``"x0,y0,z0,x1,y1,z1"`` string; ``knobs`` are the
        method's other knobs by key (:func:`methods`), e.g. ``virtual_occluders=True``.

        >>> scene.pvs("0,0,1.5,10,10,2", method="erosion")  # doctest: +SKIP
        array([  0,   3,  17, ...], dtype=uint32)
        """
        return _ids(self._native.pvs(_cell(cell), method, resolution, sweep, planes, _knobs(knobs)))

    def pvs_many(
        self,
        cells: CellsLike,
        method: str = "dual-ray",
        threads: int | None = None,
        resolution: int | None = None,
        sweep: bool = False,
        planes: int | None = None,
        **knobs: Any,
    ) -> list:
        """The PVS of many cells, computed in parallel on ``threads`` threads (all cores
        when ``None``) with the GIL released. A list of uint32 arrays, one per cell.

        >>> sets = scene.pvs_many(scene.cells(25), "dual-ray", threads=2)  # doctest: +SKIP
        """
        raw = self._native.pvs_many(
            _cells_bytes(cells), method, resolution, sweep, planes, threads, _knobs(knobs)
        )
        return [_ids(r) for r in raw]

    def visible_from(
        self,
        eye: Sequence[float],
        direction: Sequence[float],
        fov_deg: float = 60.0,
        width: int = 1920,
        height: int = 1080,
        method: str = "hzb",
    ) -> np.ndarray:
        """The objects that may be visible in one frame, by from-point occlusion culling:
        sorted object ids (uint32). An object left out is hidden from ``eye`` within the
        frustum (``hzb``, ``hom``, ``cplp``; ``hom-approx`` is not conservative).

        >>> scene.visible_from([0, 0, 1.7], [0, 1, 0], fov_deg=60, method="hzb")  # doctest: +SKIP
        array([ 0,  2, ...], dtype=uint32)
        """
        return _ids(
            self._native.visible_from(
                [float(c) for c in eye],
                [float(c) for c in direction],
                float(fov_deg),
                int(width),
                int(height),
                method,
            )
        )

    def truth(self, cell: CellLike, samples: int | None = None, resolution: int | None = None) -> dict:
        """The sampled ground-truth visible set of one cell (``sightline truth --json``);
        ``"visible"`` is a uint32 array.

        >>> scene.truth("0,0,1.5,10,10,2", samples=16)["visible"]  # doctest: +SKIP
        """
        report = json.loads(self._native.truth_json(_cell(cell), samples, resolution))
        report["visible"] = np.asarray(report["visible"], dtype=np.uint32)
        return report

    def pvs_at(self, point: Sequence[float], method: str = "portals") -> dict:
        """BSP levels: the PVS of the leaf holding ``point`` with ``"portals"`` or
        ``"portals-fast"``, as ``sightline pvs LEVEL.bsp --at X,Y,Z --json``: ``"leaf"``
        (the BSP leaf number), ``"visible"`` (face ids) and ``"visible_leaves"`` (leaf
        numbers), both uint32 arrays. A point in a wall or outside the level raises
        :class:`CellError`.

        >>> level = sightline.Scene.from_file("data/quake/dm1.bsp")             # doctest: +SKIP
        >>> level.pvs_at([200, 1000, 50], method="portals")["visible_leaves"]    # doctest: +SKIP
        array([  5,   6, ...], dtype=uint32)
        """
        try:
            p = [float(c) for c in point]
        except (TypeError, ValueError) as e:
            raise CellError(f"a point is 3 numbers x, y, z, got {point!r}") from e
        if len(p) != 3:
            raise CellError(f"a point is 3 numbers x, y, z, got {point!r}")
        report = json.loads(self._native.pvs_at_json(p, method))
        for key in ("visible", "visible_leaves"):
            report[key] = np.asarray(report[key], dtype=np.uint32)
        return report


def _scene(scene_or_path: Union[Scene, PathLike]) -> Scene:
    if isinstance(scene_or_path, Scene):
        return scene_or_path
    return Scene.from_file(scene_or_path)


def _shard(shard: Union[str, Tuple[int, int], None]) -> str | None:
    if shard is None or isinstance(shard, str):
        return shard
    i, n = shard
    return f"{int(i)}/{int(n)}"


def build(
    scene_or_path: Union[Scene, PathLike],
    cells: CellsLike,
    method: str,
    out: PathLike,
    resume: bool = False,
    shard: Union[str, Tuple[int, int], None] = None,
    resolution: int | None = None,
    sweep: bool = False,
    planes: int | None = None,
    threads: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    **knobs: Any,
) -> dict:
    """Build the ``.pvs`` of ``cells`` with ``method`` into ``out``, as ``sightline build``.

    Every finished cell goes to the journal ``out + ".journal"``; ``resume=True``
    continues an interrupted build from it without recomputing a finished cell. The file
    is written atomically and is byte-identical whatever the interruptions, threads or
    shards. ``shard="I/N"`` (or ``(I, N)``, or ``"auto/N"``) builds the cells ``k`` with
    ``k mod N == I`` into a shard file for :func:`merge`. ``progress(done, total)`` is
    called from the worker threads. Returns the statistics (cells, resumed, computed,
    bytes, seconds).

    >>> sightline.build(scene, cells, "dual-ray", "city.pvs")["cells"]  # doctest: +SKIP
    1325
    """
    sc = _scene(scene_or_path)
    return json.loads(
        _native.build(
            sc._native,
            _cells_bytes(cells),
            method,
            os.fspath(out),
            resolution,
            sweep,
            planes,
            resume,
            _shard(shard),
            threads,
            progress,
            _knobs(knobs),
        )
    )


def merge(inputs: Iterable[PathLike], out: PathLike) -> dict:
    """Merge shard files into ``out`` (atomically), as ``sightline merge``: byte-identical
    to a single build of all cells. Raises :class:`PvsFileError` if a shard is missing,
    given twice or from another build.
    """
    cells, size = _native.merge([os.fspath(p) for p in inputs], os.fspath(out))
    return {"out": os.fspath(out), "cells": cells, "bytes": size}


@dataclass(frozen=True)
class PvsQuery:
    """The answer of :meth:`PvsFile.query`: the cell containing the point and its set."""

    index: int
    cell: np.ndarray
    visible: np.ndarray
    method: str


class PvsFile:
    """An opened ``.pvs`` file: cell table and index in memory, sets decoded on demand.

    >>> f = sightline.PvsFile.open("city.pvs")  # doctest: +SKIP
    >>> len(f), f.method                        # doctest: +SKIP
    (1325, 'dual-ray')
    >>> f.query(1843.0, 5172.0, 1.7).visible    # doctest: +SKIP
    """

    def __init__(self, native: "_native.NativePvsFile") -> None:
        self._native = native
        self._header = json.loads(native.header_json())
        self._cells = _cells_array(native.cells())

    @classmethod
    def open(cls, path: PathLike) -> "PvsFile":
        """Open and check a ``.pvs`` file (:class:`PvsFileError` if it is not one or is corrupted)."""
        return cls(_native.NativePvsFile.open(os.fspath(path)))

    def __len__(self) -> int:
        return len(self._native)

    def __repr__(self) -> str:
        return f"<sightline.PvsFile {self._native.path}: {len(self)} cells, {self.method}>"

    @property
    def cells(self) -> np.ndarray:
        """The cell table, N×6 float64."""
        return self._cells

    @property
    def method(self) -> str:
        return self._header["method"]

    @property
    def params(self) -> dict:
        return dict(self._header["params"])

    @property
    def object_count(self) -> int:
        return int(self._header["objects"])

    @property
    def fingerprint(self) -> str:
        return self._header["fingerprint"]

    @property
    def shard(self) -> str | None:
        """``"I/N"`` for a shard file, else ``None``."""
        return self._header["shard"]

    def stored(self) -> np.ndarray:
        """Indices of the cells whose set is stored (all cells but in a shard file)."""
        return np.asarray(self._native.stored(), dtype=np.uint32)

    def locate(self, x: float, y: float, z: float) -> int | None:
        """The index of the cell containing the point, or ``None``."""
        return self._native.locate(float(x), float(y), float(z))

    def pvs(self, index: int) -> np.ndarray:
        """The stored set of cell ``index`` (uint32 ids)."""
        return _ids(self._native.pvs(int(index)))

    def __getitem__(self, index: int) -> np.ndarray:
        return self.pvs(index)

    def can_see(self, a: int, b: int) -> bool:
        """Whether cell ``a`` may see cell ``b``, as ``sightline query --can-see A,B``.

        Never ``False`` where the stored sets admit a sight line: through the visible
        leaves of a BSP level's file (conservative), else through an object both cells'
        sets share (conservative in closed scenes; see ``docs/engines.md``).
        """
        return self._native.can_see(int(a), int(b))

    def seen_by(self, x: float, y: float, z: float) -> np.ndarray | None:
        """The cells that may see the point, as ``sightline query --seen-by X,Y,Z``
        (uint32 cell indices; ``None`` when no cell contains the point)."""
        cells = self._native.seen_by(float(x), float(y), float(z))
        return None if cells is None else _ids(cells)

    def secondary(self, index: int) -> np.ndarray:
        """The secondary PVS of cell ``index``: the union of the sets of the cells that
        may see it, as ``sightline query --secondary CELL`` (uint32 ids)."""
        return _ids(self._native.secondary(int(index)))

    def query(self, x: float, y: float, z: float) -> PvsQuery:
        """The cell containing ``(x, y, z)`` and its set, as ``sightline query``.
        Raises :class:`CellError` if no cell contains the point (see :meth:`locate`).
        """
        for v in (x, y, z):
            if not math.isfinite(float(v)):
                raise CellError(f"the point {x},{y},{z} is not finite")
        index = self.locate(x, y, z)
        if index is None:
            raise CellError(f"no cell of {self._native.path} contains the point {x},{y},{z}")
        return PvsQuery(index=index, cell=self._cells[index].copy(), visible=self.pvs(index), method=self.method)

    def verify(self) -> None:
        """Decode every stored set and check every checksum (:class:`PvsFileError` if bad)."""
        self._native.verify()


def check(
    scene: Union[Scene, PathLike],
    pvs_path: PathLike | None = None,
    cells: Union[int, CellsLike] = 20,
    method: str | None = None,
    resolution: int | None = None,
    sweep: bool = False,
    planes: int | None = None,
    threads: int | None = None,
    strict: bool = False,
    **knobs: Any,
) -> dict:
    """A PVS against the sampled ground truth, as ``sightline check --json``.

    With ``pvs_path``: ``cells`` of the file's cells (an int), evenly spread. With
    ``method``: ``cells`` is a number of free 10 m street cells, or an N×6 array (or a
    cells.json path). ``strict=True`` raises :class:`MethodError` when a conservative
    method missed a visible object, as the command line exits with an error.

    >>> sightline.check(scene, "city.pvs", cells=5)["missed"]  # doctest: +SKIP
    0
    """
    sc = _scene(scene)
    k = None
    given = None
    if isinstance(cells, (int, np.integer)) and not isinstance(cells, bool):
        k = int(cells)
        if k <= 0:
            raise CellError(f"cells must be a positive number of cells, got {k}")
    else:
        given = _cells_bytes(cells)
    report = json.loads(
        _native.check(
            sc._native,
            None if pvs_path is None else os.fspath(pvs_path),
            method,
            given,
            k,
            resolution,
            sweep,
            planes,
            threads,
            _knobs(knobs),
        )
    )
    if strict and report["conservative"] and report["missed"] > 0:
        raise MethodError(
            f"method {report['method']} missed {report['missed']} visible object(s) — a conservativeness bug"
        )
    return report
