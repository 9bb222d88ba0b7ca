"""``python -m eyelume``: the same command line as the ``eyelume`` script (:mod:`eyelume.cli`)."""

from eyelume.cli import app

app(prog_name="eyelume")
