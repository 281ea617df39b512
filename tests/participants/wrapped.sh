#!/bin/sh
# A participant started through a wrapper, as a site script that sets up an environment first would be: it
# runs misbehaving.py as its child, not in its place (no exec), and waits for it.
# tests/integration/test_lifecycle.py, test_a_wrapped_participant_stops_with_its_wrapper.
/usr/bin/python3 "$(dirname "$0")/misbehaving.py" "$@"
status=$?
exit $status
