"""Copies of built FMUs with an edited modelDescription.xml, for the variables and units a
vendor's FMU may declare that the built-in models do not."""

import zipfile
from collections.abc import Callable
from pathlib import Path


def copy_with_description(source: Path, target: Path, edit: Callable[[str], str]) -> Path:
    """Copy the FMU ``source`` to ``target`` with its modelDescription.xml passed through ``edit``."""
    with zipfile.ZipFile(source) as original, zipfile.ZipFile(target, "w") as copy:
        for item in original.infolist():
            data = original.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = edit(data.decode()).encode()
            copy.writestr(item, data)
    return target
