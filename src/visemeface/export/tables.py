"""Tables: the activation track (CSV) and per-frame measures of a simulation (CSV)."""

from __future__ import annotations

import csv

from visemeface.export.sinks import Sink, register


@register
class TrackSink(Sink):
    """The run's activation track as CSV (:func:`visemeface.track.save_track`'s format)."""

    name = "track"
    metavar = "FILE.csv"
    help = "also write the activation track (CSV, one row a frame)"
    suffixes = (".csv",)

    def close(self) -> None:
        from visemeface.track import save_track

        save_track(self.run.track, self.tmp[0], force=True)


@register
class MeasuresSink(Sink):
    """Each frame's measures (``Frame.data``, e.g. the saliva state) as CSV: frame, time, then the measures.

    Rows stream to disk as frames arrive; numbers are written with 6 significant digits.
    """

    name = "measures"
    metavar = "FILE.csv"
    help = "also write each frame's measures as CSV (a --physics simulation's saliva state)"
    suffixes = (".csv",)
    needs_physics = True

    def open(self, run) -> None:
        super().open(run)
        self._fh = open(self.tmp[0], "w", newline="", encoding="utf-8")
        self._writer = None

    def write(self, frame) -> None:
        row = {"frame": frame.index, "time": frame.time, **frame.data}
        if self._writer is None:
            self._writer = csv.DictWriter(self._fh, fieldnames=list(row), lineterminator="\n")
            self._writer.writeheader()
        self._writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})

    def close(self) -> None:
        self._fh.close()

    def abort(self) -> None:
        fh = getattr(self, "_fh", None)
        if fh is not None:
            fh.close()
        super().abort()
