"""System B's world: a fixed-base dual-arm robot at a table, physical friction grasps,
the AgentChord atomic actions (Table IV), perceived object features, and the tasks.

Data flows one way: `world` (physics + ground truth, scoring only) -> `robot`
(what a method may touch: actions, observations) -> method. Tasks are small
declarative files (`pour_single.py`) run by one generic `task.py`.
"""
