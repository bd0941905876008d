"""The data boundary: building trend logs in, SI arrays out.

``load_zone_data(path, column_map)`` reads a CSV or Parquet trend log (wide or long),
converts units to SI, puts time stamps on UTC epoch seconds, optionally resamples onto a
uniform grid, and returns a frozen :class:`ZoneData`. See :mod:`rczone.data.columnmap`
for the TOML column-map format.
"""

from rczone.data.columnmap import Channel, ColumnMap, default_column_map, parse_column_map, read_column_map
from rczone.data.load import load_zone_data, read_table, zone_data_from_frame
from rczone.data.quality import Gap, RczoneWarning
from rczone.data.segments import Segment, constant_segments, intersect, night_segments
from rczone.data.units import DEFAULT_AIR_DENSITY, to_si
from rczone.data.zonedata import ZoneData

__all__ = [
    "DEFAULT_AIR_DENSITY",
    "Channel",
    "ColumnMap",
    "Gap",
    "RczoneWarning",
    "Segment",
    "ZoneData",
    "constant_segments",
    "default_column_map",
    "intersect",
    "load_zone_data",
    "night_segments",
    "parse_column_map",
    "read_column_map",
    "read_table",
    "to_si",
    "zone_data_from_frame",
]
