"""Scene.from_geodataframe: the GeoJSON importer's rules, and clear errors for bad frames."""

import math

import numpy as np
import pytest

gpd = pytest.importorskip("geopandas")
from shapely.geometry import LineString, MultiPolygon, Point, box  # noqa: E402

import sightline  # noqa: E402
from sightline import SceneError  # noqa: E402

from conftest import X0, Y0  # noqa: E402


def frame(crs="EPSG:2154", **columns):
    geoms = [box(X0, Y0, X0 + 20, Y0 + 20), MultiPolygon([box(X0 + 30, Y0, X0 + 50, Y0 + 20)])]
    data = {"height": [12.0, 20.0], **columns}
    return gpd.GeoDataFrame(data, geometry=geoms, crs=crs)


def test_same_scene_as_the_geojson_file(tmp_path):
    gdf = frame(name=["a", "b"], base=[0.0, 3.0])
    path = tmp_path / "f.geojson"
    gdf.to_file(path, driver="GeoJSON")
    from_frame = sightline.Scene.from_geodataframe(gdf, min_height="base", name="name")
    assert len(from_frame) == 2
    info = from_frame.info()
    assert info["scene"] == "<GeoDataFrame>"
    assert info["bounds"][5] == 20.0 and info["bounds"][2] == 0.0
    plain = sightline.Scene.from_geodataframe(gdf)
    from_file = sightline.Scene.from_file(path)
    assert plain.fingerprint == from_file.fingerprint


def test_geographic_crs_is_projected_as_the_cli(tmp_path):
    gdf = frame().to_crs(4326)
    scene = sightline.Scene.from_geodataframe(gdf)
    path = tmp_path / "wgs84.geojson"
    gdf.to_file(path, driver="GeoJSON")
    # The file stores lon/lat with 7 decimals (about 1 cm): same scene up to that.
    from_file = sightline.Scene.from_file(path, crs="wgs84")
    assert len(from_file) == len(scene) == 2
    assert np.allclose(scene.info()["bounds"], from_file.info()["bounds"], atol=0.05)
    # Projected to a local metric frame: about the 50 m × 20 m extent (Lambert-93 is
    # conformal, not equidistant, and its grid is rotated here), not degrees.
    b = scene.info()["bounds"]
    assert abs((b[3] - b[0]) - 50.0) < 1.0 and abs((b[4] - b[1]) - 20.0) < 1.0
    # Another geographic CRS is reprojected to WGS84 first: same footprints within mm.
    other = sightline.Scene.from_geodataframe(frame().to_crs(4258))
    a, b = np.array(scene.info()["bounds"]), np.array(other.info()["bounds"])
    assert np.allclose(a, b, atol=0.05)


def test_missing_column_raises():
    with pytest.raises(SceneError, match="column 'h'"):
        sightline.Scene.from_geodataframe(frame(), height="h")
    with pytest.raises(SceneError, match="column 'base'"):
        sightline.Scene.from_geodataframe(frame(), min_height="base")


@pytest.mark.parametrize("bad", [math.nan, math.inf, "tall", None])
def test_bad_heights_raise(bad):
    gdf = frame()
    gdf["height"] = [10.0, bad]
    with pytest.raises(SceneError, match="row 1"):
        sightline.Scene.from_geodataframe(gdf)


def test_negative_height_is_skipped_or_the_strict_error():
    gdf = frame()
    gdf["height"] = [10.0, -3.0]
    scene = sightline.Scene.from_geodataframe(gdf)
    assert len(scene) == 1
    skipped = [w for w in scene.info()["warnings"] if w["kind"] == "skipped-feature"]
    assert len(skipped) == 1 and "negative height" in skipped[0]["message"], skipped
    with pytest.raises(SceneError, match="feature 1"):
        sightline.Scene.from_geodataframe(gdf, strict=True)


@pytest.mark.parametrize("geom", [Point(X0, Y0), LineString([(X0, Y0), (X0 + 5, Y0)]), None])
def test_wrong_geometry_types_raise(geom):
    gdf = gpd.GeoDataFrame({"height": [5.0, 6.0]}, geometry=[box(X0, Y0, X0 + 1, Y0 + 1), geom], crs="EPSG:2154")
    with pytest.raises(SceneError, match="row 1"):
        sightline.Scene.from_geodataframe(gdf)


def test_non_metric_crs_and_non_frames_raise():
    with pytest.raises(SceneError, match="metres"):
        sightline.Scene.from_geodataframe(frame().to_crs("EPSG:2249"))  # US survey feet
    with pytest.raises(SceneError, match="GeoDataFrame"):
        sightline.Scene.from_geodataframe([1, 2, 3])
    with pytest.raises(SceneError, match="no rows"):
        sightline.Scene.from_geodataframe(frame().iloc[:0])


def test_epsg4326_label_on_metric_coordinates_is_detected_as_the_cli():
    # What gpd.read_file gives for a GeoJSON file in a local metric frame (data/*.geojson).
    gdf = frame().set_crs(4326, allow_override=True)
    scene = sightline.Scene.from_geodataframe(gdf)
    assert scene.info()["bounds"][:2] == [X0, Y0]
