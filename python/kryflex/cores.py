"""The cores a helper process beside this one may take (the report's figure helpers, report/helper.py; the
certificate's count, count_helper.py). Plain Python: the report's helpers import it without the compiled kryflex."""
import os


def idle_cores():
    """(the cores this process may run on, those less the load average of the last minute: this process counts in
    it)."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count() or 1
    try:
        return cpus, cpus - os.getloadavg()[0]
    except OSError:
        return cpus, cpus - 1.0


def core_beside(ranks):
    """Whether a helper has a core beside a run on ranks processes: the cores this process may use outnumber them,
    whatever the load average (a rule on it made a run's time depend on the minute before, its own previous run
    counting in it)."""
    return idle_cores()[0] > ranks
