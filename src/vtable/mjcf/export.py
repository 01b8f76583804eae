"""Writing the virtual table as MJCF and its meshes (`vtable export-mjcf`)."""

from __future__ import annotations

from pathlib import Path

from vtable.mjcf.builder import build
from vtable.params.specimen import Specimen
from vtable.params.virtual import virtual_table

#: the default configurations checked in under assets/mjcf/
DEFAULTS = {"bare": "none", "concrete_blocks": "concrete_blocks", "sdof_frame": "sdof_frame"}


def export_mjcf(specimen: Specimen, folder: str | Path) -> list[Path]:
    """Write model.xml (MJCF from MjSpec.to_xml) and the STL meshes it references."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    built = build(virtual_table(), specimen)
    files = []
    xml = folder / "model.xml"
    xml.write_text(built.spec.to_xml(), encoding="utf-8")
    files.append(xml)
    for name, data in sorted(built.assets.items()):
        p = folder / name
        p.write_bytes(data)
        files.append(p)
    return files
