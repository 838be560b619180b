"""The files the native code reads and writes, and their Python sides: the array file (:mod:`.array_file`, the form
of the friction table the C code reads) and the strip's nodal-field file (:mod:`.field_file`, CSV)."""
