"""The names ``import tribocosim`` offers, each imported on first use from the module that defines it (read by
``tribocosim/__init__.py`` and by the clone's own folder imported as the package, the repository's ``__init__.py``)."""

NAMES = {
    "run": "tribocosim.cosim.apps.scripting",
    "Result": "tribocosim.cosim.api",
    "load_scene": "tribocosim.cosim.scene.validate",
    "StripDrawModel": "tribocosim.components.stripdraw.model",
    "StripDrawParameters": "tribocosim.components.stripdraw.parameters",
    "make_friction_law": "tribocosim.components.stripdraw.friction",
    "export_friction": "tribocosim.cosim.apps.export_friction",
    "DebrisChoice": "tribocosim.cosim.apps.debris_state",
    "FrictionTable": "tribocosim.components.stripdraw.table",
    "read_table": "tribocosim.components.stripdraw.table",
    "write_table": "tribocosim.components.stripdraw.table",
    "DEFAULT_TABLE": "tribocosim.paths",
    "scene_file": "tribocosim.paths",
    "TribocosimError": "tribocosim.errors",
}
