"""The table-driven bad-input suite of issue 13 (driven by tests/python/commands/test_bad_inputs.py): case tables per class,
the harness that runs and checks them, and the helpers that break a copy of the Galileo scene."""
