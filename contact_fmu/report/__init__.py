"""Error against run time of the scenes' FMUs, and the stiff and extreme cases.

``contact-fmu report`` (contact_fmu.cli) runs both; modules:

- ``equations``: Eqs. (8)-(11) for scipy and the quasistationary closed form;
- ``reference``: reference solutions outside the FMU (Radau, closed forms, quadrature);
- ``sweep``: the settings swept per scene, generated from the scene's data;
- ``metrics``: error norms, observed orders, step-to-step oscillation;
- ``workprecision``: the sweep through the built FMU in fmpy, timed;
- ``stiff``: the stiff and extreme cases and their checks;
- ``output``: CSV, Markdown, plots and the documentation sections.
"""
