"""Corpora at scale: many clips from one manifest, on a Dask cluster (``visemeface batch``).

::

    import visemeface.batch as vb

    vb.write_grid_manifest("jobs.csv", n=200, outputs="video gltf")   # an example corpus
    report = vb.run("jobs.csv", "corpus/", workers=2)                    # a local Dask cluster
    report = vb.run(vb.read_manifest("jobs.csv"), "corpus/", client=Client("tcp://head:8786"))

:mod:`.manifest` reads the CSV into jobs; :mod:`.clip` makes one clip
(atomically, through the same path as ``speak``/``say``); :mod:`.runner`
sends the clips to Dask and writes ``batch_report.csv``; :mod:`.grid` writes
manifests of the GRID corpus's sentences.
"""

from visemeface.batch.clip import make_clip, output_name
from visemeface.batch.grid import grid_rows, write_grid_manifest
from visemeface.batch.manifest import COLUMNS, BadRow, Job, defaults, read_manifest, write_manifest
from visemeface.batch.runner import REPORT, local_client, read_report, run

__all__ = ["COLUMNS", "REPORT", "BadRow", "Job", "defaults", "grid_rows", "local_client", "make_clip",
           "output_name", "read_manifest", "read_report", "run", "write_grid_manifest", "write_manifest"]
