"""The project's own tests use the fixtures it ships to those who embed it (a source checkout
is not installed, so its pytest11 entry point is not registered: load the plugin by name)."""

pytest_plugins = ["eos_svc.testing.pytest_plugin"]
