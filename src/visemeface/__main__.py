"""``python -m visemeface``: the command line (:func:`visemeface.cli.main` installs the interrupt handlers first)."""
from visemeface.cli import main

raise SystemExit(main())
