"""Command signals and earthquake records."""

from vtable.signals.basic import band_limited_random, pulse, sine, time_axis
from vtable.signals.processing import (
    TableCommand,
    bandpass_trapezoid,
    differentiate,
    integrate_to_displacement,
    process_record,
    scale_record,
)
from vtable.signals.records import (
    Record,
    el_centro,
    fema_p695,
    load_record,
    read_at2,
    read_at2_folder,
    read_csv_record,
)

__all__ = [
    "Record", "TableCommand", "band_limited_random", "bandpass_trapezoid", "differentiate",
    "el_centro", "fema_p695", "integrate_to_displacement", "load_record", "process_record",
    "pulse", "read_at2", "read_at2_folder", "read_csv_record", "scale_record", "sine",
    "time_axis",
]
