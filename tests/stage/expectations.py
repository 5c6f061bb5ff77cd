"""Checks for the Python parts of stage tests: every failed expectation is
printed, and finish() exits non-zero if any failed (the check in lib.sh
then counts the test's failure)."""

import sys

_failed = []


def expect(what, condition):
    if not condition:
        print("FAIL:", what)
        _failed.append(what)


def finish():
    sys.exit(1 if _failed else 0)
