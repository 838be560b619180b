"""The exported function names and the CPU architectures of a shared library, read from its file: ELF (.so), PE
(.dll), Mach-O (.dylib), universal Mach-O (a fat header, then one Mach-O per architecture).

Test helper, standard library only: the win64, darwin and aarch64 binaries of a native FMU cannot be loaded here,
so their headers and symbol tables are read to check what they are built for and that they export the FMI
functions.
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


#: ELF e_machine, Mach-O cputype, PE machine -> architecture
ELF_MACHINES = {62: "x86_64", 183: "aarch64"}
MACHO_CPUS = {0x01000007: "x86_64", 0x0100000C: "arm64"}
PE_MACHINES = {0x8664: "x86_64", 0xAA64: "arm64"}


def fat_slices(data: bytes) -> list[tuple[int, bytes]]:
    """The (cputype, bytes) of every slice of a universal Mach-O file (<mach-o/fat.h>: big-endian fat_header
    {0xcafebabe, nfat_arch}, then fat_arch {cputype, cpusubtype, offset, size, align} per slice); each slice's
    offset a multiple of 2**align, its own header's cputype the fat_arch's."""
    magic, n = struct.unpack_from(">II", data, 0)
    if magic != 0xCAFEBABE:
        raise ValueError("not a universal Mach-O file")
    out = []
    for k in range(n):
        cputype, _, offset, size, align = struct.unpack_from(">iiIII", data, 8 + 20 * k)
        if offset % (1 << align) or offset + size > len(data):
            raise ValueError(f"slice {k}: offset {offset} not aligned to 2**{align} or past the end")
        part = data[offset:offset + size]
        if struct.unpack_from("<I", part, 0)[0] != 0xFEEDFACF or struct.unpack_from("<i", part, 4)[0] != cputype:
            raise ValueError(f"slice {k} is not the 64-bit Mach-O of cputype {cputype:#x} its fat_arch says")
        out.append((cputype, part))
    return out


def architectures(path: str | Path) -> list[str]:
    """The CPU architectures a library is built for (a universal Mach-O: one per slice, in order)."""
    data = Path(path).read_bytes()
    if data[:4] == b"\x7fELF":
        if data[4] != 2 or data[5] != 1:
            raise ValueError("not a 64-bit little-endian ELF file")
        return [ELF_MACHINES.get(struct.unpack_from("<H", data, 18)[0], "?")]
    if data[:2] == b"MZ":
        pe = struct.unpack_from("<I", data, 0x3C)[0]
        return [PE_MACHINES.get(struct.unpack_from("<H", data, pe + 4)[0], "?")]
    if struct.unpack_from(">I", data, 0)[0] == 0xCAFEBABE:
        return [MACHO_CPUS.get(cpu, "?") for cpu, _ in fat_slices(data)]
    return [MACHO_CPUS.get(struct.unpack_from("<i", data, 4)[0], "?")]


def _macho_exports(data: bytes) -> set[str]:
    if struct.unpack_from(">I", data, 0)[0] == 0xCAFEBABE:  # every slice must export them: the common names
        return set.intersection(*(_macho_exports(part) for _, part in fat_slices(data)))
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
