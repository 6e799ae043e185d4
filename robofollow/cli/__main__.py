"""`python -m robofollow.cli`."""

from robofollow.cli import run

run()
