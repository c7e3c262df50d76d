"""Model-written cost code as untrusted input: a checked language, compiled once, probed in a limited child.

    program = CostProgram.compile(source, variables={"tcp", "target", "action"})   # SandboxError if refused
    probe(source, variables, calls={"cost": (K,)}, env=sample_inputs)               # limits: CPU, memory, wall
    costs = program.bounded_call("cost", env, shape=(K,))                           # in the control loop (bounded)
"""

from kintsugi.sandbox.guard import LoopBound
from kintsugi.sandbox.language import CONSTANTS, FUNCTIONS
from kintsugi.sandbox.probe import ProbeLimits, ProbeReport, probe
from kintsugi.sandbox.program import CostProgram

__all__ = ["CONSTANTS", "CostProgram", "FUNCTIONS", "LoopBound", "ProbeLimits", "ProbeReport", "probe"]
