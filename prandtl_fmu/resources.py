"""How much memory and disk a run may take: checked up front, so that a run too large for the machine
is refused in one line before any work, instead of failing with a traceback after minutes."""
from __future__ import annotations

import os
import shutil


class ResourceError(ValueError):
    """A run would need more memory or disk than the machine has; the message is one line."""


def available_memory() -> float:
    """Bytes of memory available to a new allocation (MemAvailable on Linux; total memory elsewhere)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return float("inf")


def size_text(nbytes: float) -> str:
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if nbytes >= scale:
            return f"{nbytes / scale:.3g} {unit}"
    return f"{nbytes / 1e3:.3g} kB"


def check_memory(nbytes: float, what: str, hint: str = "") -> None:
    """ResourceError when ``what`` needs more than the memory available."""
    available = available_memory()
    if nbytes > available:
        tail = f"; {hint}" if hint else ""
        raise ResourceError(f"{what} needs about {size_text(nbytes)} of memory, {size_text(available)} "
                            f"available{tail}")


def check_disk(nbytes: float, folder: str, what: str) -> None:
    """ResourceError when ``what`` (about ``nbytes``) cannot fit on the disk of ``folder``."""
    try:
        free = shutil.disk_usage(folder).free
    except OSError:
        return
    if nbytes > free:
        raise ResourceError(f"{what} needs about {size_text(nbytes)} of disk, {size_text(free)} free in {folder}")
