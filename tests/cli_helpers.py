"""Running the `robofollow` command in process, for the tests."""

from __future__ import annotations

from robofollow import cli


def run(capsys, *argv):
    status = cli.main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err
