"""Scene input: a scene file (TOML) parsed (:mod:`.schema`), checked against the FMUs' model descriptions
(:mod:`.validate`) and against the component descriptions (:mod:`.component_checks`), every problem collected at once
(:mod:`.problems`), and the FMUs a scene names by component built on demand into the cache (:mod:`.fmucache`)."""
