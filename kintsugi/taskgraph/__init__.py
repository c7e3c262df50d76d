"""Recovery-augmented task graphs (system B, AgentChord): data model, constraints, monitors, Eq. 8 filter.

Task-free: actions, objects and features are named by a `Vocabulary` the task supplies.
"""
