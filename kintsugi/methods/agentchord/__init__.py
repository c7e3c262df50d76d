"""AgentChord (system B) on the tabletop world: the action library as a planning domain, the world's
names as a task-graph vocabulary, observation adapters, compile (composer, arranger, keyframes), the
conductor, and the registered `agentchord` method."""

from kintsugi.methods.agentchord import method, replanning  # noqa: F401 - registers the methods
