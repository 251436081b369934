"""The example notebook runs headless from top to bottom without an error."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOK = ROOT / "notebooks" / "blend_emotion_viseme.ipynb"


@pytest.mark.slow
def test_blend_notebook_executes(tmp_path, monkeypatch):
    import visemeface

    # The notebook imports the installed package. In a source checkout run with
    # PYTHONPATH=src the kernel inherits that variable; make it absolute, as the
    # kernel runs in a temporary folder.
    if Path(visemeface.__file__).resolve().is_relative_to(ROOT / "src"):
        monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(ROOT / "src"), os.environ.get("PYTHONPATH")])))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    # kernel "python3" with argv "python ..." is started on this interpreter (sys.executable)
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()  # raises CellExecutionError naming the failing cell
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outputs if o.output_type == "error"]
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) >= 2  # the chosen posture and Fig. 6
