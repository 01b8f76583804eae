"""Command signals, earthquake records and the table commands made of them."""

from vtable.signals.basic import band_limited_random, pulse, sine, time_axis
from vtable.signals.command import COMMAND_DT, DEFAULT_DURATION, Command, make_command
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
    "COMMAND_DT", "DEFAULT_DURATION", "Command", "Record", "TableCommand",
    "band_limited_random", "bandpass_trapezoid", "differentiate", "el_centro", "fema_p695",
    "integrate_to_displacement", "load_record", "make_command", "process_record", "pulse",
    "read_at2", "read_at2_folder", "read_csv_record", "scale_record", "sine", "time_axis",
]
