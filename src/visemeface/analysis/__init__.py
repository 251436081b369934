"""Mouth-opening evaluation (Leach & Maddock 2019, §4): how a mouth opens, frame by frame.

- :mod:`~visemeface.analysis.openings`: per-frame detection and Leach & Maddock's (2019)
  metrics -- the number of openings and each opening's area, width and
  height, normalised by the natural mouth width; method ``"mesh"`` (default,
  :mod:`~visemeface.analysis.innerlip`: inside the face mesh's inner-lip
  contour, what is unlike the speaker's own lips), ``"lips"``
  (:mod:`~visemeface.analysis.lips`: the region enclosed between the lips,
  segmented by colour, teeth and tongue included) or ``"seed"`` (Rec.601
  grey, median blur, dark threshold, top-level contours, optional convex hull
  and teeth handling).
- :mod:`~visemeface.analysis.mouthbox`: the mouth box found automatically in
  every frame of a real video: from face landmarks
  (:mod:`~visemeface.analysis.landmarks`, MediaPipe's face detector and face
  mesh, optional extra ``track``), else by colour (face by skin, lips by redness).
- :mod:`~visemeface.analysis.profiles`: those metrics over time as a
  DataFrame with frame-difference derivatives, the L2 distance and the
  Pearson correlation (with the best time offset) between two profiles
  (aligned by time), CSV I/O and plots.
- :mod:`~visemeface.analysis.video`: frames from a video file or an image
  folder, and the mouth-box sidecar JSON ``{"mouth_box": [x, y, w, h],
  "fps": ..., "size": [w, h]}``.
- :mod:`~visemeface.analysis.synthetic`: synthetic mouths with known
  openings (ground truth for tests and benchmarks).
- :mod:`~visemeface.analysis.augment`: altered copies of real clips (darker
  skin, a moustache, grey, low contrast, mirrored) to test the measure across
  appearances (``scripts/analysis_fairness.py``).

Example
-------
>>> from visemeface.analysis.synthetic import merging_mouth_frames
>>> from visemeface.analysis.profiles import analyze_frames
>>> df = analyze_frames(merging_mouth_frames(8, 4), (28, 78, 200, 100), fps=30)
>>> df["count"].tolist()          # two openings merge into one at frame 4
[2, 2, 2, 2, 1, 1, 1, 1]
>>> int(df["d_width"].abs().idxmax())
4
"""
