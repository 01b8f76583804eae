"""Writing the virtual table as MJCF and its meshes (`vtable export-mjcf`)."""

from __future__ import annotations

from pathlib import Path

from vtable.fileio import write_bytes, write_text
from vtable.mjcf.builder import build
from vtable.params.specimen import Specimen
from vtable.params.virtual import VirtualTable
from vtable.tables.eerc import virtual_table

#: the default configurations checked in under assets/mjcf/
DEFAULTS = {"bare": "none", "concrete_blocks": "concrete_blocks", "sdof_frame": "sdof_frame"}


def export_mjcf(specimen: Specimen, folder: str | Path,
                vt: VirtualTable | None = None) -> list[Path]:
    """Write model.xml (MJCF from MjSpec.to_xml) and the STL meshes it references, for the
    virtual table `vt` (the EERC table when None)."""
    folder = Path(folder)
    built = build(virtual_table() if vt is None else vt, specimen)
    files = [write_text(folder / "model.xml", built.spec.to_xml())]
    for name, data in sorted(built.assets.items()):
        files.append(write_bytes(folder / name, data))
    return files
