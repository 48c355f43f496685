"""The errors rotorguard raises, with the fields a program needs to point at the cause.

They mirror the command line's exit codes (docs/cli.md): a ConfigError is exit 2, an
InputFileError or CorruptFileError exit 3. A value the library itself refuses (a command of the
wrong size, an unknown log format) is a plain ValueError.
"""


class Error(Exception):
    """The base of rotorguard's own errors."""


class ConfigError(Error, ValueError):
    """An invalid scenario, vehicle or assembly file, or an invalid override.

    Attributes: file (the file, or "--set" for an override), line and column (1-based, 0 when
    unknown), key (the dotted key path, e.g. "stack.planner.v_max"), message (without location).
    """

    def __init__(self, text, file, line, column, key, message):
        super().__init__(text)
        self.file = file
        self.line = line
        self.column = column
        self.key = key
        self.message = message


class InputFileError(Error, OSError):
    """An input file that cannot be read at all (missing, a directory, permission denied)."""

    def __init__(self, text, path, reason):
        super().__init__(text)
        self.path = path
        self.reason = reason

    def __str__(self):
        return self.args[0]


class CorruptFileError(Error, ValueError):
    """An input file whose content is damaged; byte_offset is where the damage was found."""

    def __init__(self, text, path, byte_offset, message):
        super().__init__(text)
        self.path = path
        self.byte_offset = byte_offset
        self.message = message
