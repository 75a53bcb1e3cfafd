"""The seed paper, regenerated: figures, interaction examples and the experiment's trend.

One role per module:

* :mod:`ocp.gallery.interaction` -- Section IV-B impedance/admittance references and their shaped,
  actuator-aware versions (numbers only);
* :mod:`ocp.gallery.experiment` -- Section V Cases 1, 4, 5 (+ the optimised reference) in closed loop,
  with the paper's measured figures beside them (numbers only);
* :mod:`ocp.gallery.figures` -- matplotlib renderings (Agg canvas, no pyplot);
* :mod:`ocp.gallery.build` -- :func:`build_gallery`: all figures as PNG + SVG, the table, ``index.html``.

Run ``thrustshape gallery --out DIR`` or ``python -m ocp.gallery --out DIR``. Importing this package
imports no plotting code.
"""
