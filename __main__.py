"""``python -m htn``: the same as the ``htn`` command."""

from htn.cli.start import main

main()
