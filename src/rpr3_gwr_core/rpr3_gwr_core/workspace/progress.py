"""Progress reports of long builds: the core calls back, its caller shows them.

Every build function that can take seconds takes an optional keyword
``progress``, a callable ``progress(stage, fraction)``: ``stage`` names what
runs (str), ``fraction`` in [0, 1] is how much of the call's whole work is
done, non-decreasing.  The core never prints; the command line draws a bar,
the ROS builder logs.
"""

__all__ = ["part"]


def _silent(stage, fraction):
    pass


def part(progress, low=0.0, high=1.0, within=None):
    """The callback of a step that takes ``[low, high]`` of its caller's work.

    Parameters
    ----------
    progress : callable or None
        The caller's ``progress(stage, fraction)``.
    low, high : float
        The fractions of the caller's work at the step's start and end.
    within : str, optional
        Put before the step's stage names (``"within: stage"``), where the
        step's own names would not tell which part of the work runs.

    Returns
    -------
    callable
        ``report(stage, fraction)`` taking the step's own fraction in [0, 1];
        it does nothing when ``progress`` is None.
    """
    if progress is None:
        return _silent
    prefix = "" if within is None else f"{within}: "
    return lambda stage, fraction: progress(prefix + stage, low + (high - low) * fraction)
