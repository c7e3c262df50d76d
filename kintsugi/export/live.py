"""Watching a trial while it runs: a live page (frames written for a browser, optionally served over HTTP on
this machine's loopback, for a laptop on the other end of `ssh -L`) or MuJoCo's passive viewer where a display
exists. Both are observers attached to the robot before the method starts (`run_trial(attach=...)`); they
render and read, never act, so a watched trial is the same trial.
"""

from __future__ import annotations

import http.server
import json
import os
import threading
from functools import partial
from pathlib import Path
from typing import Any

import cv2

from kintsugi.core.errors import ConfigError
from kintsugi.methods.policy.drivers import driver_for

PAGE = """<!doctype html><meta charset="utf-8"><title>kintsugi live</title>
<style>body{font-family:sans-serif;background:#111;color:#ddd;margin:1em}img{max-width:100%;image-rendering:pixelated}
</style><h3 id="head">kintsugi: waiting for the first frame</h3><img id="frame" alt="live frame"><pre id="story"></pre>
<script>
async function tick(){
  try{const s=await (await fetch('status.json?'+Date.now())).json();
      document.getElementById('head').textContent=s.title+'  t = '+s.t.toFixed(2)+' s, step '+s.step+(s.done?' (done)':'');
      document.getElementById('story').textContent=s.story.join('\\n');
      document.getElementById('frame').src='frame.jpg?'+s.frame;}catch(e){}
  setTimeout(tick,250);}
tick();
</script>
"""


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the stdlib's name
        return None


class LivePage:
    """Writes `frame.jpg`, `status.json` and `index.html` into `out` every `every_s` of sim time; with `port`,
    serves them at http://127.0.0.1:<port>/ while the trial runs."""

    def __init__(self, out: str | Path, title: str, every_s: float = 0.1, port: int | None = None) -> None:
        self.out = Path(out)
        self.out.mkdir(parents=True, exist_ok=True)
        (self.out / "index.html").write_text(PAGE)
        self.title, self.every_s = title, every_s
        self.frames = 0
        self.ticks = 0
        self._story: list[str] = []
        self._next = 0.0
        self.driver: Any = None
        self.server: http.server.ThreadingHTTPServer | None = None
        if port is not None:
            try:
                self.server = http.server.ThreadingHTTPServer(
                    ("127.0.0.1", port), partial(_Quiet, directory=str(self.out)))
            except OSError as exc:
                raise ConfigError(f"cannot serve the live page on 127.0.0.1:{port}: {exc}") from None
            threading.Thread(target=self.server.serve_forever, daemon=True).start()

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.server.server_address[1]}/" if self.server else str(self.out / "index.html")

    def attach(self, robot: Any, log: Any) -> None:
        self.driver = driver_for(robot)
        self.driver.record_ticks(self._on_tick)
        self._write(done=False)

    def echo(self, line: str) -> None:
        from rich.errors import MarkupError
        from rich.text import Text

        try:
            line = Text.from_markup(line).plain
        except MarkupError:
            pass
        self._story = (self._story + [line])[-12:]

    def _on_tick(self, command: Any) -> None:
        self.ticks += 1
        if self.driver.sim_time + 1e-9 >= self._next:
            self._next = self.driver.sim_time + self.every_s
            self._write(done=False)

    def _write(self, done: bool) -> None:
        frame = cv2.cvtColor(self.driver.render(), cv2.COLOR_RGB2BGR)
        tmp = self.out / "frame.tmp.jpg"
        cv2.imwrite(str(tmp), frame)
        os.replace(tmp, self.out / "frame.jpg")
        self.frames += 1
        status = {"title": self.title, "t": self.driver.sim_time, "step": self.ticks, "done": done,
                  "frame": self.frames, "story": self._story}
        (self.out / "status.tmp.json").write_text(json.dumps(status))
        os.replace(self.out / "status.tmp.json", self.out / "status.json")

    def finish(self) -> None:
        if self.driver is not None:
            self._write(done=True)
        if self.server is not None:
            self.server.shutdown()
            self.server.server_close()


class PassiveViewer:
    """MuJoCo's passive viewer on the evaluation world, synced every control period (needs a display)."""

    def __init__(self) -> None:
        if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
            raise ConfigError("--viewer needs a display (DISPLAY is not set); over SSH use --live DIR "
                              "[--port N] and open the page in a browser")
        self.handle: Any = None

    def attach(self, robot: Any, log: Any) -> None:
        import mujoco.viewer

        driver = driver_for(robot)
        self.handle = mujoco.viewer.launch_passive(driver.world.model, driver.world.data)
        driver.record_ticks(lambda command: self.handle.sync() if self.handle.is_running() else None)

    def finish(self) -> None:
        if self.handle is not None:
            self.handle.close()
