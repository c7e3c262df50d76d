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


class SandboxError(KintsugiError):
    """Model-written code was rejected or failed; `kind` says how (forbidden, syntax, shape, ...), the message
    says where (line, column) and what to write instead."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(message)
        self.kind = kind

    def __reduce__(self):  # noqa: ANN204 - picklable across worker processes despite the extra argument
        return (type(self), (self.kind, str(self)))
