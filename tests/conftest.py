"""Suite-wide settings: hypothesis runs derandomized (the same examples on every machine, so CI
cannot fail by chance) and without an example database in the work tree."""

from hypothesis import settings

settings.register_profile("ipmc", derandomize=True, database=None, deadline=None)
settings.load_profile("ipmc")
