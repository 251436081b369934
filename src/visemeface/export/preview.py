"""A self-contained web preview: one HTML page that plays a .glb animation in sync with its sound.

The page inlines three.js (vendored package data, MIT licence: ``vendor/three-LICENSE.txt``, bundled
by ``scripts/vendor_three.sh``), the glb and the audio (base64), so it opens from ``file://`` with no
network. The animation follows the sound's clock (``mixer.setTime(audio.currentTime)``); play/pause and
a scrubber; ``#t=1.5`` in the address shows that time. For checks the page publishes
``window.vfPreview`` (``setTime``, ``weights()``, ``pixel(x, y)``) and writes its state as JSON into
``<pre id="status">`` (time, morph weights, the centre pixel, any error).
"""

from __future__ import annotations

import base64
import html
import math
import json
import struct
from pathlib import Path

from visemeface.errors import InputError
from visemeface.export.sinks import Sink, register
from visemeface.outputs import atomic_output

VENDOR = Path(__file__).resolve().parent / "vendor"
#: Sound formats browsers play, by suffix.
AUDIO_TYPES = {".wav": "audio/wav", ".mp3": "audio/mpeg", ".ogg": "audio/ogg", ".oga": "audio/ogg",
               ".flac": "audio/flac", ".m4a": "audio/mp4"}

_STYLE = """body{margin:0;background:#202428;color:#eee;font:14px sans-serif;overflow:hidden}
#view{display:block;width:100vw;height:calc(100vh - 44px)}
#bar{display:flex;gap:10px;align-items:center;height:44px;padding:0 12px;box-sizing:border-box}
#scrub{flex:1}#status{display:none}"""

_MAIN = r"""
(function () {
  const status = { ready: false, time: 0, weights: {}, pixel: null, errors: [] };
  const show = () => { document.getElementById('status').textContent = JSON.stringify(status); };
  window.addEventListener('error', (e) => { status.errors.push(String(e.message)); show(); });
  const oldError = console.error;
  console.error = function (...a) { status.errors.push(a.map(String).join(' ')); show(); oldError.apply(console, a); };
  const bytes = Uint8Array.from(atob(document.getElementById('glb').textContent.trim()), (c) => c.charCodeAt(0));
  const canvas = document.getElementById('view');
  const renderer = new VF3.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.outputColorSpace = VF3.SRGBColorSpace;
  renderer.setPixelRatio(1);
  const scene = new VF3.Scene();
  scene.background = new VF3.Color(0x202428);
  scene.add(new VF3.HemisphereLight(0xffffff, 0x404040, 1.6));
  const sun = new VF3.DirectionalLight(0xffffff, 1.8);
  sun.position.set(0.3, 0.5, 1.0);
  scene.add(sun);
  const camera = new VF3.PerspectiveCamera(30, 1, 0.01, 10);
  const audio = document.getElementById('audio');
  const scrub = document.getElementById('scrub'), play = document.getElementById('play');
  const label = document.getElementById('time');
  let mixer = null, mesh = null, duration = 1, clockStart = null, clockT = 0, playing = false;
  function resize() {
    const w = canvas.clientWidth || 640, h = canvas.clientHeight || 480;
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
  }
  function now() {
    if (audio) return audio.currentTime;
    return playing ? clockT + (performance.now() - clockStart) / 1000 : clockT;
  }
  function setTime(t) {
    t = Math.max(0, Math.min(duration, t));
    if (audio) audio.currentTime = t; else { clockT = t; clockStart = performance.now(); }
    draw(t);
  }
  function draw(t) {
    if (!mixer) return;
    mixer.setTime(t);
    renderer.render(scene, camera);
    status.time = t;
    status.weights = weights();
    status.pixel = pixel(Math.floor(canvas.width / 2), Math.floor(canvas.height / 2));
    scrub.value = String(Math.round(1000 * t / duration));
    label.textContent = t.toFixed(2) + ' s';
    show();
  }
  function weights() {
    const out = {};
    if (!mesh) return out;
    for (const [name, i] of Object.entries(mesh.morphTargetDictionary || {})) out[name] = mesh.morphTargetInfluences[i];
    return out;
  }
  function pixel(x, y) {
    const gl = renderer.getContext(), p = new Uint8Array(4);
    gl.readPixels(x, canvas.height - 1 - y, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, p);
    return [p[0], p[1], p[2]];
  }
  function loop() {
    if (playing) {
      const t = now();
      if (!audio && t >= duration) { playing = false; clockT = duration; play.textContent = 'Play'; }
      draw(Math.min(t, duration));
    }
    requestAnimationFrame(loop);
  }
  play.addEventListener('click', () => {
    if (playing) {
      playing = false;
      if (audio) audio.pause(); else clockT = now();
      play.textContent = 'Play';
    } else {
      if (now() >= duration - 1e-3) setTime(0);
      playing = true;
      if (audio) audio.play(); else clockStart = performance.now();
      play.textContent = 'Pause';
    }
  });
  if (audio) audio.addEventListener('ended', () => { playing = false; play.textContent = 'Play'; });
  scrub.addEventListener('input', () => setTime(duration * Number(scrub.value) / 1000));
  window.addEventListener('resize', () => { resize(); draw(now()); });
  new VF3.GLTFLoader().parse(bytes.buffer, '', (gltf) => {
    scene.add(gltf.scene);
    gltf.scene.traverse((o) => { if (o.isMesh && o.morphTargetInfluences) mesh = o; });
    const box = new VF3.Box3().setFromObject(gltf.scene), c = box.getCenter(new VF3.Vector3());
    const size = box.getSize(new VF3.Vector3());
    camera.position.set(c.x, c.y, c.z + 2.2 * Math.max(size.x, size.y));
    camera.lookAt(c);
    mixer = new VF3.AnimationMixer(gltf.scene);
    const clip = gltf.animations[0];
    duration = clip ? clip.duration : 0;
    if (clip) { const a = mixer.clipAction(clip); a.setLoop(VF3.LoopOnce); a.clampWhenFinished = true; a.play(); }
    resize();
    status.ready = true;
    status.duration = duration;
    status.morphTargets = Object.keys(mesh ? mesh.morphTargetDictionary : {});
    const m = /[#&]t=([0-9.]+)/.exec(location.hash);
    setTime(m ? Number(m[1]) : 0);
    window.vfPreview = { setTime, weights, pixel, status };
    requestAnimationFrame(loop);
  }, (err) => { status.errors.push('glb: ' + err); show(); });
})();
"""


def three_bundle() -> str:
    """The vendored three.js bundle (global ``VF3``)."""
    path = VENDOR / "three-preview.min.js"
    if not path.is_file():
        raise InputError("the vendored three.js bundle is missing (run scripts/vendor_three.sh)", path)
    return path.read_text(encoding="utf-8")


def preview_html(glb: bytes, audio: bytes | None = None, audio_type: str = "audio/wav",
                 title: str = "visemeface") -> str:
    """The page (module docstring) for a .glb's bytes and optional sound bytes."""
    if glb[:4] != b"glTF":
        raise InputError("not a binary glTF (.glb) file")
    sound = (f'<audio id="audio" preload="auto" src="data:{audio_type};base64,{base64.b64encode(audio).decode()}">'
             "</audio>") if audio else ""
    return "\n".join([
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>",
        '<canvas id="view"></canvas>',
        '<div id="bar"><button id="play">Play</button><input id="scrub" type="range" min="0" max="1000" value="0">'
        '<span id="time">0.00 s</span></div>', '<pre id="status"></pre>', sound,
        f'<script id="glb" type="application/octet-stream">{base64.b64encode(glb).decode()}</script>',
        f"<script>{three_bundle()}</script>", f"<script>{_MAIN}</script>", "</body></html>", ""])


def glb_duration(glb: bytes) -> float:
    """Largest keyframe time of a .glb's animations (0 when none): checks the container too."""
    if len(glb) < 20 or glb[:4] != b"glTF":
        raise InputError("not a readable binary glTF (no glTF header)")
    length, kind = struct.unpack_from("<I4s", glb, 12)
    if kind != b"JSON":
        raise InputError("not a readable binary glTF (no JSON chunk)")
    try:
        doc = json.loads(glb[20:20 + length])
        times = [float(doc["accessors"][s["input"]].get("max", [0.0])[0])
                 for a in doc.get("animations", []) for s in a["samplers"]]
    except (ValueError, KeyError, IndexError, TypeError, AttributeError) as exc:
        raise InputError(f"not a readable binary glTF ({type(exc).__name__}: {str(exc)[:60]})") from None
    duration = float(max(times, default=0.0))
    if not (math.isfinite(duration) and duration >= 0):
        raise InputError(f"not a readable binary glTF (animation time {duration:g} s)")
    return duration


def write_preview(path, glb: bytes, audio_path=None, title: str = "visemeface", force: bool = False) -> None:
    """Write the preview page of ``glb`` (bytes) with the sound file ``audio_path`` inlined."""
    audio, kind = None, "audio/wav"
    if audio_path is not None:
        audio_path = Path(audio_path)
        kind = AUDIO_TYPES.get(audio_path.suffix.lower())
        if kind is None:
            raise InputError(f"a browser cannot play this sound; use one of {', '.join(AUDIO_TYPES)}", audio_path)
        audio = audio_path.read_bytes()
    text = preview_html(glb, audio, kind, title)
    with atomic_output(path, force) as tmp:
        tmp.write_text(text, encoding="utf-8")


@register
class PreviewSink(Sink):
    """The run as a self-contained HTML page (the --gltf animation with the sound inlined)."""

    name = "preview"
    metavar = "FILE.html"
    help = ("also write a self-contained web page (three.js, offline) that plays the animation, with its sound "
            "where the run has one (no FILE: beside the video, named after it)")
    suffixes = (".html",)
    beside_video = ".html"

    def close(self) -> None:
        from visemeface.export.gltf import write_run_glb

        run = self.run
        if run.rig is None or run.track is None:
            raise InputError("--preview needs a speech run (speak, say or simulate)", self.path)
        glb = self.tmp[0].with_name(self.tmp[0].name + ".glb")
        try:
            write_run_glb(glb, run)
            data = glb.read_bytes()
        finally:
            glb.unlink(missing_ok=True)
        write_preview(self.tmp[0], data, run.audio, title=str(run.extra.get("source") or "visemeface"), force=True)
