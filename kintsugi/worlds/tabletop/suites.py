"""Named system-B campaigns: AgentChord's Table I cells, fixed by name, for every tabletop task.

`table1` is the paper's simulation table at drop p = 0.10 (every method of the comparison, the drop
condition, 20 trials); `table1-p05` the same at p = 0.05. Each is one campaign (one task, one p):
`kintsugi bench <task> --suite table1`. `bench/bench_agentchord_table.py --run` runs both suites on the
Table I tasks and prints the table with Wilson intervals. A user's `--set` overrides go on top.
"""

from __future__ import annotations


from kintsugi.core.suite import Suite

TABLE1_METHODS = ("inner-monologue", "doremi", "rekep", "code-as-monitor", "agentchord-bt", "agentchord")
"""The paper's Table I columns (IM, DoReMi, ReKep, CaM, AgentChord) plus the AC-BT ablation."""


def _table1(p: float, name: str, companion: str) -> Suite:
    return Suite(name=name, description=f"AgentChord Table I cell: every method, held object dropped with p = {p} "
                 "per atomic action, 20 trials", methods=TABLE1_METHODS, shapes=("default",),
                 conditions=("drop",), trials=20, overrides={"disturbance.drop_p": p}, companion=companion)


SUITES: dict[str, Suite] = {s.name: s for s in (_table1(0.10, "table1", "table1-p05"),
                                                _table1(0.05, "table1-p05", "table1"))}
