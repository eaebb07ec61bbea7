"""``python -m htn``: the same as the ``htn`` command."""
from htn.cli.main import main

main()
