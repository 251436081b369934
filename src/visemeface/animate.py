"""An utterance to a finished run: the library path of ``speak``, ``say`` and ``batch``.

::

    Utterance --activation_track--> track --KinematicMotion / SimulatedMotion--> motion --pipeline.run--> sinks

:func:`animate` is everything those commands do after they have an utterance
and their outputs: build the activation track (visemes, coarticulation,
emotions), the motion (the kinematic rig, or the FEM face with ``physics``)
and stream it into the sinks through :func:`visemeface.pipeline.run`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from visemeface.errors import InputError, table_name

#: Longest utterance one run animates (s): longer means wrong units far more often than a 3-hour take.
MAX_UTTERANCE_S = 3 * 3600


def parse_emotions(specs, known: Iterable[str]) -> dict[str, float]:
    """``["happiness=0.6", "anger"]`` -> ``{"happiness": 0.6, "anger": 1.0}``, names checked and every
    weight in 0..1 (as a text's emotion tags): the one reader of ``--emotion`` for every command."""
    from visemeface.postures.library import parse_weights

    known = list(known)
    emotions = {}
    for name, weight in parse_weights(specs).items():
        name = table_name(name, known, "emotion")
        emotions[name] = emotions.get(name, 0.0) + weight
    for name, weight in emotions.items():
        if not 0.0 <= weight <= 1.0:
            given = [s for s in ([specs] if isinstance(specs, str) else specs)
                     for part in str(s).split(",") if part.partition("=")[0].strip().lower() == name]
            more = " (its weights given add up)" if len(given) > 1 else ""
            raise InputError(f"emotion weight {weight:g} for {name!r} is not in 0..1{more}")
    return emotions


def _to_the_audio(audio, utterance, fps):
    """The utterance made to last as long as ``audio`` (the face at rest after its last phone, so the
    recording is never cut), with a warning where they differ by more than a frame."""
    import warnings

    from visemeface.pipeline import check_audio

    audio_s, speech_s = check_audio(audio), utterance.end
    if abs(audio_s - speech_s) > 1.0 / fps:
        what = ("the audio is padded with silence to the animation" if audio_s < speech_s else
                "the face rests after the last phone until the audio ends")
        warnings.warn(f"{audio}: the audio lasts {audio_s:.2f} s, the transcript {speech_s:.2f} s; {what}",
                      stacklevel=4)
    return utterance.lasting(audio_s)


def recording_acoustics(audio):
    """The :class:`~visemeface.speech.acoustics.Acoustics` of a recording (path)."""
    from visemeface.speech.acoustics import analyse
    from visemeface.speech.audio import read_audio

    return analyse(*read_audio(audio))


def jali_factors(utterance, acoustics=None, articulation: float = 1.0):
    """Per-segment (ja, li) of :mod:`visemeface.speech.articulation` for ``utterance``: from ``acoustics``
    where given, else from the phones' lexical stress (:meth:`Utterance.phone_stress`); None
    (the tabled visemes) at articulation 0 or with neither."""
    from visemeface.speech.articulation import acoustic_scales, check_articulation, stress_scales

    if check_articulation(articulation) == 0:
        return None
    seg = utterance.segments
    if acoustics is not None:
        return acoustic_scales(acoustics, seg["start"], seg["end"], seg["phoneme"], articulation)
    stress = utterance.phone_stress()
    if stress is not None:
        return stress_scales(seg["phoneme"], *stress, articulation=articulation)
    return None


def simulated_motion(rig, track, physics: str, settings=None):
    """The FEM face of ``rig.face`` driven by ``track`` (every setting checked before any step); ``settings``
    default to :meth:`PhysicsSettings.speech` (the lips refined along the seam: the motion renders
    the refined face and writes ``rig.face``'s vertices, its first ones)."""
    from visemeface.motion import SimulatedMotion
    from visemeface.physics.drive import face_simulation

    return SimulatedMotion(face_simulation(rig.face, rig, track, physics, settings), face=rig.face)


def animate(utterance, sinks: list, render=None, *, rig=None, emotions=None, interp: str | None = None,
            fps: float = 30.0, audio=None, physics: str | None = None, physics_settings=None,
            checkpoint: Callable | None = None, resume: bool = False, show_progress: bool = True, source: str = "text",
            blink: bool = True, articulation: float = 1.0, gestures: bool = True, seed: int = 0, also=(),
            final: bool = False):
    """Animate ``utterance`` into ``sinks``; returns the run's :class:`~visemeface.pipeline.RunStats`.

    Parameters
    ----------
    utterance : Utterance
    sinks : list of Sink
        The outputs (checked by their constructors before any work).
    render : RenderSettings, optional
    rig : MuscleRig, optional
        Default: the embedded face's rig.
    emotions : list of str or mapping, optional
        ``NAME[=W]`` specs or ``{name: weight}`` (a dict or a pandas Series); names are checked against
        the rig's expression table and each weight must be in 0..1.
    interp : str, optional
        Interpolation between visemes (default: coarticulation).
    fps : float
    audio : Path, optional
        Sound muxed into a video sink: the animation lasts at least as long (the face at rest after
        the last phone); a length mismatch is warned about.
    physics : str, optional
        ``"sticky"`` or ``"elastic"`` for the FEM face; None for the kinematic rig.
    physics_settings : PhysicsSettings, optional
    checkpoint : callable, optional
        ``checkpoint(motion) -> RunCheckpoint | None`` for a resumable motion.
    resume : bool
        Continue from the checkpoint and reuse kept frames.
    source : str
        Where the utterance came from (a transcript's path, or "text"), recorded by exports that name it.
    blink : bool
        Blink at a natural rate (:func:`visemeface.speech.blinks.blink_utterance`, deterministic).
    articulation : float
        0..2: how much the recording's acoustics (``audio``), else the text's lexical stress, widen or
        narrow each phone's jaw and lip action (:mod:`visemeface.speech.articulation`, JALI); 0 plays the
        tabled visemes exactly.
    gestures : bool
        Head nods and turns, brow raises and gaze from the prosody (:mod:`visemeface.speech.gestures`):
        the brows and eyes in the track, the head's rotation in the run's ``extra["head"]`` (degrees,
        yaw/pitch/roll per frame) for the renderer, Live Link and glTF.
    seed : int
        The gestures' (deterministic) random choices.
    also, final :
        More staged outputs put in place with the sinks', and whether they are the command's last
        (:func:`visemeface.pipeline.run`).
    """
    from visemeface import pipeline
    from visemeface.motion import KinematicMotion
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_expressions, load_visemes
    from visemeface.export.sinks import check_physics_outputs
    from visemeface.speech.timeline import MODES, activation_track

    from visemeface.speech.utterance import Utterance

    utterance = Utterance.of(utterance, "animate")
    check_physics_outputs([s.name for s in sinks], physics, option="")
    if utterance.end > MAX_UTTERANCE_S:
        raise InputError(f"the transcript lasts {utterance.end:.0f} s, over the {MAX_UTTERANCE_S} s limit of one "
                         "run (wrong time units? try --format / --sample-rate)")
    if audio is not None and any(s.name == "video" for s in sinks):
        utterance = _to_the_audio(audio, utterance, fps)
    rig = rig if rig is not None else default_rig()
    emotions = parse_emotions(emotions, load_expressions(rig=rig).index)
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    acoustics = recording_acoustics(audio) if audio is not None and (articulation > 0 or gestures) else None
    track = activation_track(utterance, load_visemes(rig=rig), fps=fps, mode=interp or MODES[0],
                             emotions=emotions or None, ranges=ranges,
                             jali=jali_factors(utterance, acoustics, articulation))
    if blink:
        from visemeface.speech.blinks import blink_utterance

        track = blink_utterance(track, rig, utterance)
    extra = {}
    if gestures:
        from visemeface.speech.gestures import add_face_gestures, speech_gestures

        moves = speech_gestures(utterance, len(track), fps, acoustics, seed=seed)
        extra["track_without_gestures"] = track     # for outputs whose vocabulary has no brow raise (VRM)
        track = add_face_gestures(track, rig.names, moves)
        extra["head"] = moves.head
    if physics is None or physics == "none":
        motion = KinematicMotion(rig, track)
    else:
        motion = simulated_motion(rig, track, physics, physics_settings)
    return pipeline.run(motion, sinks, render,
                        info=dict(audio=audio, rig=rig, track=track, end_time=utterance.end,
                                  extra={"motion_key": motion.key(), "utterance": utterance,
                                         "interp": interp or MODES[0], "source": source, **extra}),
                        checkpoint=checkpoint(motion) if checkpoint is not None else None,
                        resume=resume, show_progress=show_progress, also=also, final=final)
