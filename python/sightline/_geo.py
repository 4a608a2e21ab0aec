"""GeoDataFrame → GeoJSON text for the Rust GeoJSON importer.

The conversion only checks what GeoJSON cannot carry faithfully (geometry types, NaN
heights, a missing column, the CRS); every other rule — ring repair, degenerate
footprints, negative heights, ``min_height`` above the top, the WGS84 projection — is the
importer's, so a GeoDataFrame and the same data as a ``.geojson`` give the same scene.
"""

from __future__ import annotations

import json
import math
from typing import Any, Optional, Tuple

from ._native import SceneError

_POLYGONAL = ("Polygon", "MultiPolygon")


def _crs_mode(gdf: Any) -> Tuple[Any, Optional[str]]:
    """The frame to export and the importer's CRS mode for it."""
    crs = gdf.crs
    if crs is None:
        return gdf, None  # detected from the coordinates, as the CLI does
    if crs.is_geographic:
        if crs.to_epsg() == 4326 or crs.equals("OGC:CRS84"):
            # What GeoPandas reports for any GeoJSON file (RFC 7946), lon/lat or not:
            # detect from the coordinates, as the CLI does for the same file.
            return gdf, None
        return gdf.to_crs(4326), "wgs84"
    if crs.is_projected:
        units = {a.unit_name.lower() for a in crs.axis_info[:2]}
        if not units <= {"metre", "meter", "m"}:
            raise SceneError(
                f"the GeoDataFrame's CRS {crs.to_string()} is in {', '.join(sorted(units))}, not metres: "
                "reproject it (gdf.to_crs(...)) to a metric CRS"
            )
        return gdf, "projected"
    raise SceneError(f"the GeoDataFrame's CRS {crs.to_string()} is neither projected nor geographic")


def _number(value: Any, column: str, row: int) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise SceneError(f"row {row}: column '{column}' is {value!r}, not a number") from None
    if not math.isfinite(v):
        raise SceneError(f"row {row}: column '{column}' is {value!r}, not a finite number of metres")
    return v


def geodataframe_to_geojson(
    gdf: Any, height: str, min_height: Optional[str], name: Optional[str]
) -> Tuple[str, Optional[str]]:
    """GeoJSON FeatureCollection text (row k = feature k) and the importer's CRS mode."""
    if not hasattr(gdf, "geometry") or not hasattr(gdf, "columns"):
        raise SceneError(f"expected a geopandas GeoDataFrame, got {type(gdf).__name__}")
    for col in (height, min_height, name):
        if col is not None and col not in gdf.columns:
            raise SceneError(f"column '{col}' is not in the GeoDataFrame (columns: {', '.join(map(str, gdf.columns))})")
    if len(gdf) == 0:
        raise SceneError("the GeoDataFrame has no rows")
    gdf, mode = _crs_mode(gdf)
    from shapely.geometry import mapping

    features = []
    heights = gdf[height].tolist()
    bases = gdf[min_height].tolist() if min_height is not None else None
    names = gdf[name].tolist() if name is not None else None
    for k, geom in enumerate(gdf.geometry):
        if geom is None or geom.is_empty:
            raise SceneError(f"row {k}: no geometry (empty or missing)")
        if geom.geom_type not in _POLYGONAL:
            raise SceneError(
                f"row {k}: geometry {geom.geom_type} is not a Polygon or MultiPolygon "
                "(keep the footprints: gdf[gdf.geom_type.isin(['Polygon', 'MultiPolygon'])])"
            )
        props = {"height": _number(heights[k], height, k)}
        if bases is not None:
            props["min_height"] = _number(bases[k], min_height, k)
        feature = {"type": "Feature", "geometry": mapping(geom), "properties": props}
        if names is not None and names[k] is not None:
            feature["id"] = str(names[k])
        features.append(feature)
    try:
        text = json.dumps({"type": "FeatureCollection", "features": features}, allow_nan=False)
    except ValueError:
        raise SceneError("a geometry has NaN or infinite coordinates") from None
    return text, mode
