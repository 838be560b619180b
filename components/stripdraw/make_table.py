"""Regenerate the stand-in friction table from the closed form (until mesoscale results exist).

Usage: ``python -m components.stripdraw.make_table [OUT.npz]`` (default: models/friction_table.npz).
The table says ``"provenance": "closed_form"`` in its metadata.
"""

from __future__ import annotations

import sys

from components.paths import DEFAULT_TABLE
from components.stripdraw.friction import closed_form_table
from components.stripdraw.table import write_table


def main(argv: list[str] | None = None) -> int:
    """Write the closed-form table and print its path and hash."""
    args = sys.argv[1:] if argv is None else argv
    out = args[0] if args else DEFAULT_TABLE
    digest = write_table(out, closed_form_table())
    print(f"wrote {out} (provenance closed_form, sha256 {digest[:16]}...)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
