"""An independent proving ground for the model check: random rigs, loggers and excitations.

Shares NO code with ``ocp/``: its own motor + propeller physics (:mod:`.physics`, written from the
equations of a brushed DC motor, not from ``ocp.model.effects``), its own integrator (exponential step for the
armature current, classical RK4 for the mechanics, a command FIFO for transport delays), its own
loggers (:mod:`.logger`) and excitations (:mod:`.excite`). :func:`make_case` draws one case from a seed.
Only plain numbers and numpy arrays leave the package.
"""

from tests.proving_ground.cases import Case, make_case

__all__ = ["Case", "make_case"]
