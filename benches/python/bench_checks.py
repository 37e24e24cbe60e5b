"""Checks the benchmark scripts make of what they compare, in every mode (`--smoke` runs them on
a few iterations, from scripts/test): a failed check ends the script with a message and a
non-zero exit, so that a benchmark whose sides drift apart or whose figures go missing is caught
rather than printed."""
import math
import sys


def fail(message):
    """Ends the script: exit status 1, `message` on standard error."""
    print(f"bench check failed: {message}", file=sys.stderr)
    sys.exit(1)


def positive(name, value):
    """`value` if it is a finite number above 0 (a time, a ratio of times); fails otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        fail(f"{name} is {value!r}, not a finite positive number")
    return value


def agree(name, ours, theirs, tolerance):
    """The largest |ours - theirs| over two equally long sequences of numbers if it is at most
    `tolerance` (0: bit for bit); fails otherwise, or if the lengths differ or a value is not finite."""
    ours, theirs = list(ours), list(theirs)
    if len(ours) != len(theirs) or not ours:
        fail(f"{name}: {len(ours)} values against {len(theirs)}")
    if not all(math.isfinite(v) for v in ours + theirs):
        fail(f"{name}: a value is not finite")
    worst = max(abs(a - b) for a, b in zip(ours, theirs))
    if not worst <= tolerance:
        fail(f"{name}: they differ by up to {worst:.3e} (at most {tolerance:.1e} allowed)")
    return worst
