"""Sub-commands of the ``visemeface`` CLI, one module each (see :mod:`visemeface.cli`)."""
