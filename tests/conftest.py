"""Suite-wide settings: property tests draw the same examples on every run (deterministic CI),
and a loaded 2-core machine never fails a property test on timing alone."""

from hypothesis import settings

settings.register_profile("kintsugi", derandomize=True, deadline=None, print_blob=True)
settings.load_profile("kintsugi")
