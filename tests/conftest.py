"""Test-suite settings: property tests draw the same examples on every run and worker (a
failure is reproducible, CI cannot pass or fail by luck)."""

from hypothesis import settings

settings.register_profile("deterministic", derandomize=True, print_blob=True)
settings.load_profile("deterministic")
