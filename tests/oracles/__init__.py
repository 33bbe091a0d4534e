"""Test oracles: readable numpy reference implementations ("twins") of compiled code, kept out of
the package. Only the tests import them; each is held equal to its compiled counterpart by a test.
Import them as ``from tests.oracles.<module> import ...`` (the repository root on ``sys.path``, as
``python -m pytest`` from the root has it)."""
