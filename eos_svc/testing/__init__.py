"""Test support for planners that embed the EOS: a pytest plugin with real URDF hands.

Installed with eos_svc and loaded by pytest through its ``pytest11`` entry point
(:mod:`eos_svc.testing.pytest_plugin`), so a project that plans with the EOS tests its own
agents against every registered hand without writing fixtures of its own.
"""
