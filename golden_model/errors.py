"""The one exception type the command line turns into a one-line message."""


class RasterhwError(ValueError):
    """Bad input or an unsupported parameter.

    Raised by loaders, the pipeline and the HDL drivers with a message that names the
    offending value; ``rasterhw`` prints ``error: <message>`` and exits with status 2.
    """
