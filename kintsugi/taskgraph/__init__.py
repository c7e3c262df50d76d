"""Recovery-augmented task graphs (system B, AgentChord): data model, constraints, monitors, Eq. 8 filter.

Task-free: actions, objects and features are named by a `Vocabulary` the task supplies.

    graph = TaskGraph.from_json(reply_text, vocabulary)        # composer reply -> checked graph
    graph = augment(graph, parse_proposals(arranger_reply))     # + monitors and recovery branches
    result = forward_filter(graph)                              # Eq. 8: drop backward branches
    bank = MonitorBank.for_edge(result.graph.edge("e1"), features_at_edge_start)
    firing = bank.step(features)                                # every control step (Eq. 12)
"""

from kintsugi.taskgraph.augment import RecoveryProposal, augment, parse_proposals
from kintsugi.taskgraph.base import GraphError
from kintsugi.taskgraph.constraints import TEMPLATES, Constraint
from kintsugi.taskgraph.features import ArmState, Features, ObjectState
from kintsugi.taskgraph.forward import Branch, FilterResult, cost_to_go, forward_filter, next_edge
from kintsugi.taskgraph.geometry import Point
from kintsugi.taskgraph.model import ActionCall, Edge, Monitor, Node, TaskGraph
from kintsugi.taskgraph.monitor import Firing, MonitorBank
from kintsugi.taskgraph.render import to_dot, write_graph_picture
from kintsugi.taskgraph.vocabulary import Vocabulary

__all__ = [
    "ActionCall", "ArmState", "Branch", "Constraint", "Edge", "Features", "FilterResult", "Firing", "GraphError",
    "Monitor", "MonitorBank", "Node", "ObjectState", "Point", "RecoveryProposal", "TEMPLATES", "TaskGraph",
    "Vocabulary", "augment", "cost_to_go", "forward_filter", "next_edge", "parse_proposals", "to_dot",
    "write_graph_picture",
]
