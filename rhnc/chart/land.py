"""Land from the offline coastline mask: the land cells of global-land-mask as polygons in the local plane.

``global-land-mask`` (PyPI, MIT) ships the GLOBE land/sea mask inside the package (2.5 MB, no
download at run time): one boolean per 30 arc-second cell, 1/120 deg, i.e. 0.93 km in
latitude and 0.93 km x cos(latitude) in longitude (0.58 km at 51 N).  Lakes count as land.
A coastline from it is therefore good to about half a kilometre: a passage's declared
clearance should be at least that (every shipped passage declares 1 nm or more) and the
no-go polygons of a passage (:mod:`rhnc.chart.chart`) add the detail the mask lacks.

Importing the package unpacks the whole mask (0.9 GB, some 10 s), so a run does not: the
land of a passage's chart is extracted once into a GeoJSON file beside it
(:func:`land_geojson`, by ``scripts/make_passages.py``) and read from there like any other
polygon file.  The cells are read exactly as the package's ``is_land`` reads them (row
``int((90 - lat) * 120)``, column ``int((lon + 180) * 120)``), merged into runs along each
row and united in latitude/longitude, so a point is on land in the file exactly when
``is_land`` says so.
"""

from __future__ import annotations

import numpy as np

from orchestrator.geometry import wrap_longitude_deg

#: Cells per degree of the mask (30 arc-seconds).
CELLS_PER_DEG = 120


def land_mask_cells(south_deg: float, west_deg: float, north_deg: float, east_deg: float):
    """The mask's rows and columns covering a box, and its land flags there.

    Returns
    -------
    row_lat_deg : ndarray (nr + 1,)
        Latitude [deg] of the northern edge of each row, then the southern edge of the last.
    col_lon_deg : ndarray (nc + 1,)
        Longitude [deg] of the western edge of each column, then the eastern edge of the last.
    land : ndarray (nr, nc) bool
    """
    from global_land_mask import globe

    if not (-90.0 <= south_deg < north_deg <= 90.0):
        raise ValueError(f"chart bounds: south {south_deg} must lie below north {north_deg}, within +-90 deg")
    west = float(wrap_longitude_deg(west_deg))
    east = west + float(east_deg - west_deg) % 360.0 if east_deg != west_deg else west
    if not east > west:
        raise ValueError(f"chart bounds: east {east_deg} must differ from west {west_deg}")
    row0 = int((90.0 - north_deg) * CELLS_PER_DEG)
    row1 = min(int(np.ceil((90.0 - south_deg) * CELLS_PER_DEG)), 180 * CELLS_PER_DEG)
    col0 = int(np.floor((west + 180.0) * CELLS_PER_DEG))
    col1 = int(np.ceil((east + 180.0) * CELLS_PER_DEG))
    rows = np.arange(row0, row1)
    cols = np.arange(col0, col1)
    ocean = globe._mask[rows[:, None], cols[None, :] % (360 * CELLS_PER_DEG)]  # noqa: SLF001 the mask itself
    row_lat = 90.0 - np.arange(row0, row1 + 1) / CELLS_PER_DEG
    col_lon = -180.0 + np.arange(col0, col1 + 1) / CELLS_PER_DEG
    return row_lat, col_lon, ~np.asarray(ocean, dtype=bool)


def land_geojson(south_deg: float, west_deg: float, north_deg: float, east_deg: float) -> dict:
    """The mask's land within a box as a GeoJSON FeatureCollection of polygons (lon, lat) [deg]."""
    import shapely

    row_lat, col_lon, land = land_mask_cells(south_deg, west_deg, north_deg, east_deg)
    boxes = []
    for i in range(land.shape[0]):
        row = np.concatenate([[False], land[i], [False]]).astype(np.int8)
        edges = np.flatnonzero(np.diff(row))
        for j0, j1 in zip(edges[::2], edges[1::2], strict=True):
            boxes.append(shapely.box(col_lon[j0], row_lat[i + 1], col_lon[j1], row_lat[i]))
    united = shapely.union_all(boxes) if boxes else shapely.MultiPolygon()
    parts = list(getattr(united, "geoms", [united])) if not united.is_empty else []
    features = [{"type": "Feature", "properties": {"name": f"land {k}"},
                 "geometry": shapely.geometry.mapping(shapely.set_precision(part, 1e-7))}
                for k, part in enumerate(parts)]
    return {"type": "FeatureCollection", "features": features,
            "properties": {"source": "global-land-mask (GLOBE 30 arc-second land/sea mask)",
                           "bounds_deg": [south_deg, west_deg, north_deg, east_deg]}}
