"""Task-free control: batched MuJoCo rollouts, MPPI with ESS temperature, force feedback, system identification."""

from kintsugi.control.feedback import ForceFeedbackConfig, force_feedback
from kintsugi.control.mppi import MPPI, CostFn, IterationStats, MPPIConfig
from kintsugi.control.rollout import RolloutBatch, RolloutEngine, get_state
from kintsugi.control.temperature import mppi_weights, temperature_for_ess

__all__ = [
    "CostFn", "ForceFeedbackConfig", "IterationStats", "MPPI", "MPPIConfig", "RolloutBatch",
    "RolloutEngine", "force_feedback", "get_state", "mppi_weights", "temperature_for_ess",
]
