"""One root exception type; every message says what to do next."""


class KintsugiError(Exception):
    """Root of every error kintsugi raises on purpose."""


class ConfigError(KintsugiError):
    """A config key or value is wrong; the message names it."""


class UnknownNameError(KintsugiError):
    """A registry, body, site or camera name does not exist; lists the ones that do."""


class SimulationDiverged(KintsugiError):
    """The physics produced NaN/Inf or MuJoCo raised a warning that invalidates the trial."""


class ReasoningError(KintsugiError):
    """A reasoner reply could not be parsed or validated, even after one repair attempt."""
