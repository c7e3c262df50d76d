"""Method registry: name -> factory(task_config, reasoner_settings) -> method object."""

from kintsugi.registry import Registry

METHODS: Registry = Registry("method")
