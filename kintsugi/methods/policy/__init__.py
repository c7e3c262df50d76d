"""The `policy` method: policies run closed-loop through the step-level drivers (see `method`)."""

from kintsugi.methods.policy import method  # noqa: F401 - registers the method

