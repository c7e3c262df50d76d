"""AgentChord (system B) on the tabletop world: the action library as a planning domain, the world's
names as a task-graph vocabulary, observation adapters, and (when registered) the method itself."""
