"""The table-driven bad-input suite (driven by tests/python/commands/test_bad_inputs.py): case tables per class,
the harness that runs and checks them, and the helpers that break a copy of the Galileo scene."""
