"""Write the closed-form law (Eq. 9 + 23) as a friction table, for comparison with the shipped one.

Usage: ``python -m tribocosim.components.stripdraw.make_table OUT.npz``. The table says
``"provenance": "closed_form"`` in its metadata. The shipped ``models/friction_table.npz`` is the
mesoscale table of the quick preset (``tribocosim surrogate build --preset quick``); this command
refuses to overwrite it.
"""

from __future__ import annotations

import sys
from pathlib import Path

from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw.friction import closed_form_table
from tribocosim.components.stripdraw.table import write_table


def main(argv: list[str] | None = None) -> int:
    """Write the closed-form table to OUT and print its path and hash (exit 2 on bad usage)."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m tribocosim.components.stripdraw.make_table OUT.npz", file=sys.stderr)
        return 2
    out = Path(args[0])
    if out.resolve() == Path(DEFAULT_TABLE).resolve():
        print(f"error: {out} is the shipped mesoscale table; write the closed form elsewhere",
              file=sys.stderr)
        return 2
    digest = write_table(out, closed_form_table())
    print(f"wrote {out} (provenance closed_form, sha256 {digest[:16]}...)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
