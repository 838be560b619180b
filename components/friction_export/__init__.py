"""Exports of the strip-draw friction law for forming FE codes: LS-DYNA, Abaqus and a neutral JSON table.

An export writes what the runtime evaluates: the table law through the same native core (:mod:`.exported_law`),
sampled finely enough for the target code's own linear interpolation (:mod:`.grid_refinement`), with its provenance
(table hash, parameters, debris state, units) in its header (:mod:`.export_header`), in the target's format
(:mod:`.lsdyna_deck`, :mod:`.abaqus_friction`, :mod:`.neutral_table`), all files of an export or none
(:mod:`.file_set`); :mod:`.export_run` does one export. A calibration is a calibrated table or a calibration file,
the shipped ones by name (:mod:`.named_calibration`: ``paper``, the default); the user friction routines are
:mod:`.user_routines`. The command ``tribocosim export``, the debris state from a multi-pass strip-draw test or a
sheet point's slide, and the paper calibration's file are applications (:mod:`tribocosim.cosim.apps.export_friction`,
:mod:`tribocosim.cosim.apps.debris_state`, :mod:`tribocosim.cosim.apps.paper_calibration`).
"""

from tribocosim.lazy import lazy_exports

__getattr__, __all__ = lazy_exports(__name__, {
    "ExportedLaw": ".exported_law",
    "load_law": ".exported_law",
    "run_export": ".export_run",
    "ExportRequest": ".export_run",
    "DebrisState": ".export_run",
    "FORMATS": ".export_run",
    "UNIT_SYSTEMS": ".export_units",
})
