"""``--set NAME=VALUE`` on every command line: one reading of the items, each command typing the values its way.

:func:`split_settings` turns the items into ``{name: text}`` in order (a later item of the same name wins) and refuses
an item that is not ``NAME=VALUE`` with the option's name; the scene commands read each text as a TOML value
(:func:`tribocosim.cosim.scene.schema.parse_overrides`), the friction commands as the strip-draw parameter it names
(:func:`tribocosim.components.stripdraw.settings.parse_settings`).
"""

from __future__ import annotations


def split_settings(items, option: str = "--set", what: str = "NAME", error=None) -> dict[str, str]:
    """``{name: value text}`` of ``NAME=VALUE`` items (both stripped); ``error`` (default ParameterError) for an item
    without ``=`` or a name, naming ``option`` and the item."""
    if error is None:
        from tribocosim.errors import ParameterError as error
    out = {}
    for item in items:
        name, sep, value = str(item).partition("=")
        if not sep or not name.strip():
            raise error(f"{option} {item!r}: expected {what}=VALUE")
        out[name.strip()] = value.strip()
    return out
