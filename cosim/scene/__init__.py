"""Scene input: a scene file (TOML) parsed once (:mod:`.schema`), its values checked once, a component FMU's against
the component's declaration (:mod:`.component_checks`) and a path FMU's against its model description
(:mod:`.validate`, ``load_scene``: the one pipeline), every problem collected at once (:mod:`.problems`), the FMUs'
model-description summaries and extracted folders cached by content (:mod:`.fmu_files`), and the FMUs a scene names
by component built on demand into the cache (:mod:`.fmucache`)."""
