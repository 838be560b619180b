"""The exported function names of a shared library, read from its file: ELF (.so), PE (.dll), Mach-O (.dylib).

Test helper, standard library only: the win64 and darwin64 binaries of a native FMU cannot be loaded here,
so their symbol tables are read to check that they export the fmi2 functions.
"""

from __future__ import annotations

import struct
from pathlib import Path


def _pe_exports(data: bytes) -> set[str]:
    pe = struct.unpack_from("<I", data, 0x3C)[0]
    if data[pe:pe + 4] != b"PE\0\0":
        raise ValueError("not a PE file")
    n_sections = struct.unpack_from("<H", data, pe + 6)[0]
    opt_size = struct.unpack_from("<H", data, pe + 20)[0]
    opt = pe + 24
    magic = struct.unpack_from("<H", data, opt)[0]
    dirs = opt + (112 if magic == 0x20B else 96)  # PE32+ or PE32
    export_rva = struct.unpack_from("<I", data, dirs)[0]
    sections = []
    sec = opt + opt_size
    for k in range(n_sections):
        vsize, vaddr, rsize, raddr = struct.unpack_from("<IIII", data, sec + 40 * k + 8)
        sections.append((vaddr, max(vsize, rsize), raddr))

    def offset(rva: int) -> int:
        for vaddr, size, raddr in sections:
            if vaddr <= rva < vaddr + size:
                return rva - vaddr + raddr
        raise ValueError(f"RVA {rva:#x} in no section")

    if export_rva == 0:
        return set()
    exp = offset(export_rva)
    n_names = struct.unpack_from("<I", data, exp + 24)[0]
    names_rva = struct.unpack_from("<I", data, exp + 32)[0]
    names = set()
    table = offset(names_rva)
    for k in range(n_names):
        start = offset(struct.unpack_from("<I", data, table + 4 * k)[0])
        names.add(data[start:data.index(b"\0", start)].decode())
    return names


def _macho_exports(data: bytes) -> set[str]:
    magic = struct.unpack_from("<I", data, 0)[0]
    if magic != 0xFEEDFACF:
        raise ValueError("not a 64-bit little-endian Mach-O file")
    ncmds = struct.unpack_from("<I", data, 16)[0]
    pos = 32
    names = set()
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", data, pos)
        if cmd == 0x2:  # LC_SYMTAB
            symoff, nsyms, stroff, _ = struct.unpack_from("<IIII", data, pos + 8)
            for k in range(nsyms):
                strx, ntype, nsect, _, _ = struct.unpack_from("<IBBHQ", data, symoff + 16 * k)
                if ntype & 0x01 and (ntype & 0x0E) == 0x0E and nsect != 0:  # N_EXT, N_SECT: defined, external
                    start = stroff + strx
                    name = data[start:data.index(b"\0", start)].decode()
                    names.add(name[1:] if name.startswith("_") else name)
        pos += size
    return names


def _elf_exports(data: bytes) -> set[str]:
    if data[:4] != b"\x7fELF" or data[4] != 2:
        raise ValueError("not a 64-bit ELF file")
    shoff = struct.unpack_from("<Q", data, 0x28)[0]
    shentsize, shnum = struct.unpack_from("<HH", data, 0x3A)
    sections = [struct.unpack_from("<IIQQQQIIQQ", data, shoff + k * shentsize) for k in range(shnum)]
    names = set()
    for sh in sections:
        if sh[1] != 11:  # SHT_DYNSYM
            continue
        off, size, link, entsize = sh[4], sh[5], sh[6], sh[9]
        stroff = sections[link][4]
        for k in range(size // entsize):
            name, info, _, shndx = struct.unpack_from("<IBBH", data, off + k * entsize)
            if (info >> 4) in (1, 2) and shndx != 0:  # global or weak, defined
                start = stroff + name
                names.add(data[start:data.index(b"\0", start)].decode())
    return names


def exported_functions(path: str | Path) -> set[str]:
    """The names a shared library exports (without Mach-O's leading underscore)."""
    data = Path(path).read_bytes()
    if data[:4] == b"\x7fELF":
        return _elf_exports(data)
    if data[:2] == b"MZ":
        return _pe_exports(data)
    return _macho_exports(data)
