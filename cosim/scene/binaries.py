"""Whether an FMU carries a complete shared library for this machine, checked before any library is loaded.

A truncated library (an interrupted copy or download) can pass the dynamic loader and then crash the process with
a bus error when a page past the end of the file is touched: no message, and no clean-up of what the process had
extracted. So the scene check reads the library's headers from the FMU's zip and refuses a file that is shorter
than they say it is:

- ELF (Linux): the program header table and every segment's file image (``p_offset + p_filesz``, ELF-64 and
  ELF-32, either byte order), and the section header table, lie within the file;
- Mach-O (macOS): a universal file's slices (``offset + size`` of each ``fat_arch``) lie within the file, and in
  every 64-bit slice the load commands and each segment's file image (``fileoff + filesize``) lie within its slice;
- PE (Windows): the section table and every section's raw data (``PointerToRawData + SizeOfRawData``) lie within
  the file.

This checks the structure the loader maps, not the code: a library that is complete but wrong still loads.
"""

from __future__ import annotations

import struct
import sys
from pathlib import Path


def host_platform() -> str:
    """The FMI 2.0 platform folder of this machine's libraries (64-bit: ``linux64``, ``darwin64``, ``win64``)."""
    return "win64" if sys.platform.startswith("win") else "darwin64" if sys.platform == "darwin" else "linux64"


def library_in_fmu(model_identifier: str) -> str:
    """The path inside an FMI 2.0 FMU of the library this machine loads (its platform folder and suffix, as fmpy
    and every FMI 2.0 importer look for it)."""
    suffix = ".dll" if sys.platform.startswith("win") else ".dylib" if sys.platform == "darwin" else ".so"
    return f"binaries/{host_platform()}/{model_identifier}{suffix}"


def fmu_binary_problem(fmu: str | Path, model_identifier: str) -> str | None:
    """Why the FMU's library for this machine cannot be loaded safely (absent, or shorter than its headers say),
    or None."""
    import zipfile

    inside = library_in_fmu(model_identifier)
    with zipfile.ZipFile(fmu) as z:
        try:
            data = z.read(inside)
        except KeyError:
            return f"{Path(fmu).name} has no library for this machine ({inside})"
    problem = truncation(data)
    return f"{Path(fmu).name}: its library {inside} is truncated or damaged ({problem})" if problem else None


def truncation(data: bytes) -> str | None:
    """What part of a shared library lies beyond the end of its bytes (``data``), or None when it is whole."""
    try:
        if data[:4] == b"\x7fELF":
            return _elf(data)
        if data[:4] in (b"\xca\xfe\xba\xbe", b"\xcf\xfa\xed\xfe"):
            return _macho(data)
        if data[:2] == b"MZ":
            return _pe(data)
    except struct.error as exc:  # a header cut short
        return f"its headers are cut short ({exc})"
    return f"{len(data)} bytes that are not an ELF, Mach-O or PE library"


def _beyond(what: str, end: int, size: int) -> str | None:
    return f"{what} ends at byte {end}, the file has {size}" if end > size else None


def _elf(d: bytes) -> str | None:
    if len(d) < 52:
        return f"an ELF header needs at least 52 bytes, the file has {len(d)}"
    wide, order = d[4] == 2, "<" if d[5] == 1 else ">"
    if wide:
        if len(d) < 64:
            return f"an ELF-64 header needs 64 bytes, the file has {len(d)}"
        phoff, shoff = struct.unpack_from(order + "QQ", d, 32)
        phentsize, phnum, shentsize, shnum = struct.unpack_from(order + "HHHH", d, 54)
        segment = order + "IIQQQQQQ"  # type, flags, offset, vaddr, paddr, filesz, memsz, align
    else:
        phoff, shoff = struct.unpack_from(order + "II", d, 28)
        phentsize, phnum, shentsize, shnum = struct.unpack_from(order + "HHHH", d, 42)
        segment = order + "IIIIIIII"  # type, offset, vaddr, paddr, filesz, memsz, flags, align
    problem = _beyond("the program header table", phoff + phnum * phentsize, len(d))
    if problem:
        return problem
    for k in range(phnum):
        fields = struct.unpack_from(segment, d, phoff + k * phentsize)
        offset, filesz = (fields[2], fields[5]) if wide else (fields[1], fields[4])
        problem = _beyond(f"segment {k}", offset + filesz, len(d))
        if problem:
            return problem
    return _beyond("the section header table", shoff + shnum * shentsize, len(d)) if shnum else None


def _macho(d: bytes) -> str | None:
    if d[:4] == b"\xca\xfe\xba\xbe":  # universal: big-endian fat_header and fat_arch entries
        if len(d) < 8:
            return "a universal header needs 8 bytes"
        (n,) = struct.unpack_from(">I", d, 4)
        problem = _beyond("the universal header", 8 + 20 * n, len(d))
        if problem:
            return problem
        for k in range(n):
            _, _, offset, size, _ = struct.unpack_from(">iiIII", d, 8 + 20 * k)
            problem = _beyond(f"slice {k}", offset + size, len(d)) or _thin(d[offset:offset + size])
            if problem:
                return problem
        return None
    return _thin(d)


def _thin(d: bytes) -> str | None:
    """A 64-bit little-endian Mach-O file: its load commands and segments within it."""
    if len(d) < 32 or d[:4] != b"\xcf\xfa\xed\xfe":
        return "a slice is not a 64-bit Mach-O file"
    ncmds, sizeofcmds = struct.unpack_from("<II", d, 16)
    problem = _beyond("the load commands", 32 + sizeofcmds, len(d))
    if problem:
        return problem
    pos = 32
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", d, pos)
        if cmd == 0x19:  # LC_SEGMENT_64: segname[16], vmaddr, vmsize, fileoff, filesize
            name = d[pos + 8:pos + 24].rstrip(b"\0").decode("ascii", "replace")
            fileoff, filesize = struct.unpack_from("<QQ", d, pos + 40)
            problem = _beyond(f"segment {name}", fileoff + filesize, len(d))
            if problem:
                return problem
        pos += max(size, 8)
    return None


def _pe(d: bytes) -> str | None:
    if len(d) < 64:
        return f"a DOS header needs 64 bytes, the file has {len(d)}"
    (pe,) = struct.unpack_from("<I", d, 60)
    problem = _beyond("the PE header", pe + 24, len(d))
    if problem:
        return problem
    nsections, = struct.unpack_from("<H", d, pe + 6)
    optional, = struct.unpack_from("<H", d, pe + 20)
    table = pe + 24 + optional
    problem = _beyond("the section table", table + 40 * nsections, len(d))
    if problem:
        return problem
    for k in range(nsections):
        name = d[table + 40 * k:table + 40 * k + 8].rstrip(b"\0").decode("ascii", "replace")
        raw_size, raw_offset = struct.unpack_from("<II", d, table + 40 * k + 16)
        problem = _beyond(f"section {name}", raw_offset + raw_size, len(d)) if raw_size else None
        if problem:
            return problem
    return None
