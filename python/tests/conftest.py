"""Small generated scenes: a grid of blocks with streets between them (fast to build)."""

import json
from pathlib import Path

import pytest

# Projected metres far from lon/lat ranges, so no WGS84 detection kicks in.
X0, Y0 = 640_000.0, 6_860_000.0
BLOCK, STREET, N = 20.0, 10.0, 4


def block_features(n=N):
    feats = []
    for j in range(n):
        for i in range(n):
            x = X0 + i * (BLOCK + STREET)
            y = Y0 + j * (BLOCK + STREET)
            ring = [[x, y], [x + BLOCK, y], [x + BLOCK, y + BLOCK], [x, y + BLOCK], [x, y]]
            feats.append(
                {
                    "type": "Feature",
                    "id": f"b{i}-{j}",
                    "geometry": {"type": "Polygon", "coordinates": [ring]},
                    "properties": {"height": 6.0 + 4.0 * ((i * 7 + j * 3) % 5)},
                }
            )
    return feats


@pytest.fixture(scope="session")
def scene_path(tmp_path_factory) -> Path:
    p = tmp_path_factory.mktemp("scene") / "blocks.geojson"
    p.write_text(json.dumps({"type": "FeatureCollection", "features": block_features()}))
    return p


@pytest.fixture(scope="session")
def scene(scene_path):
    import sightline

    return sightline.Scene.from_file(scene_path)


@pytest.fixture(scope="session")
def street_cell():
    """A 10 m cell in the street between the first two columns of blocks."""
    x = X0 + BLOCK
    return [x, Y0, 1.5, x + STREET, Y0 + STREET, 2.0]
