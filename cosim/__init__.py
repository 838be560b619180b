"""Co-simulation: scenes, the master algorithms on fmpy, results, reports and the CLI."""
