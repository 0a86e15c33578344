"""Exit codes of ``spectral-igl`` and the error that carries one."""
from __future__ import annotations

__all__ = ["EXIT_OK", "EXIT_ERROR", "EXIT_USAGE", "EXIT_INPUT", "EXIT_MISSING", "CLIError"]

EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_INPUT, EXIT_MISSING = 0, 1, 2, 3, 4


class CLIError(Exception):
    """An error with the exit code it maps to."""

    def __init__(self, message, code=EXIT_ERROR):
        super().__init__(message)
        self.code = code
