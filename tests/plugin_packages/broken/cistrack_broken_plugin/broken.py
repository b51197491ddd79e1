"""A plugin module whose import fails, as a real broken plugin's would."""
import cistrack_dependency_that_is_not_installed  # noqa: F401
