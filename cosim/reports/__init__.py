"""Reports: error against run time (work-precision) and numerical stability (``tribocosim report``).

Modules
    :mod:`~tribocosim.cosim.reports.metrics` the error metric and the cheapest-setting selection;
    :mod:`~tribocosim.cosim.reports.stability_criterion` the stability criterion, growth detection, bisection for the largest stable step;
    :mod:`~tribocosim.cosim.reports.monodromy` the exact one-step map of Jacobi/0 on the two-mass oscillator;
    :mod:`~tribocosim.cosim.reports.runner` master runs with a wall-time budget and early stops, judged by the criterion;
    :mod:`~tribocosim.cosim.reports.accuracy` / :mod:`~tribocosim.cosim.reports.stability_report` the families (one function each);
    :mod:`~tribocosim.cosim.reports.near_pcrit` the accuracy family of iterative coupling at 0.99 p_crit (``near_pcrit``);
    :mod:`~tribocosim.cosim.reports.markdown` CSV, PNG and Markdown output; :mod:`~tribocosim.cosim.reports.oscfmus` the test FMUs.

The command line is :mod:`tribocosim.cosim.apps.report_cli`. Nothing here is imported by ``tribocosim run``.
"""
