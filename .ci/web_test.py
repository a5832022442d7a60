#!/usr/bin/env python3
"""The browser build tested in a real browser: headless Chromium over its DevTools protocol (a small
WebSocket client on the standard library, so nothing to install but Chromium).

Usage: web_test.py URL OUTDIR NATIVE_METRICS_JSON BROKEN_SCENE NATIVE_CHECK_LINE

Checks (exit status 1 on the first failure):
  1. the page draws the default scene: both views in a screenshot, not blank; first frame within 5 s
     of navigation;
  2. ?scene=meninges&script=meninges_careful finishes with the links cut and the score of the native
     `dissect run` (metrics.json given), the score to 0.1;
  3. a broken scene opened through the page's file picker shows the same `file:line:column` error as
     native `dissect check`;
  4. the mouse and keyboard work the instruments: key 1 takes the forceps and a left drag in the
     trainee's view grasps the tissue and lifts it (the page's `data-live`);
  5. G hides the exercise's regions and planned incision in the trainee's view and shows them again.
Writes default.png, regions_off.png, mouse.png, script.png and broken.png into OUTDIR and prints the
figures.
"""

import base64
import json
import os
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.request

FIRST_FRAME_BUDGET_MS = 5000


class Cdp:
    """A minimal DevTools client: one WebSocket, requests answered in order, events skipped."""

    def __init__(self, ws_url):
        rest = ws_url[len("ws://"):]
        host_port, path = rest.split("/", 1)
        host, port = host_port.split(":")
        self.sock = socket.create_connection((host, int(port)), timeout=120)
        key = base64.b64encode(os.urandom(16)).decode()
        req = (f"GET /{path} HTTP/1.1\r\nHost: {host_port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
               f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n")
        self.sock.sendall(req.encode())
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise RuntimeError("DevTools closed the connection during the handshake")
            head += chunk
        if b" 101 " not in head.split(b"\r\n", 1)[0]:
            raise RuntimeError("DevTools refused the WebSocket: " + head.decode(errors="replace"))
        self.buf = head.split(b"\r\n\r\n", 1)[1]
        self.next_id = 0

    def _read(self, n):
        while len(self.buf) < n:
            chunk = self.sock.recv(1 << 20)
            if not chunk:
                raise RuntimeError("DevTools closed the connection")
            self.buf += chunk
        out, self.buf = self.buf[:n], self.buf[n:]
        return out

    def _recv(self):
        data = b""
        while True:
            b0, b1 = self._read(2)
            n = b1 & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._read(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._read(8))[0]
            data += self._read(n)
            if b0 & 0x80:
                return data.decode()

    def _send(self, text):
        payload = text.encode()
        mask = os.urandom(4)
        n = len(payload)
        if n < 126:
            head = struct.pack(">BB", 0x81, 0x80 | n)
        elif n < 65536:
            head = struct.pack(">BBH", 0x81, 0x80 | 126, n)
        else:
            head = struct.pack(">BBQ", 0x81, 0x80 | 127, n)
        masked = bytes(b ^ mask[i % 4] for i, b in enumerate(payload))
        self.sock.sendall(head + mask + masked)

    def call(self, method, **params):
        self.next_id += 1
        self._send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            msg = json.loads(self._recv())
            if msg.get("id") == self.next_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})

    def eval(self, expr):
        r = self.call("Runtime.evaluate", expression=expr, returnByValue=True)
        return r.get("result", {}).get("value")

    def wait_for(self, expr, timeout, what):
        end = time.time() + timeout
        while time.time() < end:
            v = self.eval(expr)
            if v:
                return v
            time.sleep(0.2)
        err = self.eval("document.getElementById('error') && document.getElementById('error').textContent")
        raise RuntimeError(f"timed out after {timeout} s waiting for {what}; page error: {err!r}")

    def screenshot(self, path):
        data = self.call("Page.captureScreenshot", format="png")["data"]
        with open(path, "wb") as f:
            f.write(base64.b64decode(data))


def ppm_pixels(png):
    """The screenshot's pixels through ImageMagick's `convert` (PNG to binary PPM)."""
    raw = subprocess.run(["convert", png, "ppm:-"], check=True, capture_output=True).stdout
    fields, pos = [], 0
    while len(fields) < 4:
        while raw[pos:pos + 1].isspace():
            pos += 1
        if raw[pos:pos + 1] == b"#":
            pos = raw.index(b"\n", pos) + 1
            continue
        end = pos
        while not raw[end:end + 1].isspace():
            end += 1
        fields.append(raw[pos:end])
        pos = end
    w, h = int(fields[1]), int(fields[2])
    return w, h, raw[pos + 1:pos + 1 + w * h * 3]


def region_stats(pixels, rect):
    """Mean and spread of the grey level, and the number of distinct colours, inside rect."""
    w, h, data = pixels
    x0, y0, rw, rh = (int(round(v)) for v in rect)
    x1, y1 = min(w, x0 + rw), min(h, y0 + rh)
    greys, colours = [], set()
    for y in range(max(0, y0), y1, 3):
        row = data[(y * w) * 3:(y * w + w) * 3]
        for x in range(max(0, x0), x1, 3):
            r, g, b = row[x * 3], row[x * 3 + 1], row[x * 3 + 2]
            greys.append((r + g + b) / 3)
            colours.add((r >> 3, g >> 3, b >> 3))
    if not greys:
        return 0.0, 0.0, 0
    mean = sum(greys) / len(greys)
    spread = (sum((v - mean) ** 2 for v in greys) / len(greys)) ** 0.5
    return mean, spread, len(colours)


def check_views(cdp, png, label):
    views = json.loads(cdp.eval("document.body.dataset.views || '[]'") or "[]")
    if len(views) != 2:
        raise RuntimeError(f"{label}: the page reports {len(views)} views, expected 2 (trainee, observer)")
    pixels = ppm_pixels(png)
    for name, rect in zip(["trainee", "observer"], views):
        mean, spread, colours = region_stats(pixels, rect)
        print(f"  {label}: {name} view {rect}: mean grey {mean:.0f}, spread {spread:.1f}, {colours} colours")
        if spread < 8 or colours < 20:
            raise RuntimeError(f"{label}: the {name} view looks blank (spread {spread:.1f}, {colours} colours)")


def guide_pixels(pixels, rect):
    """Pixels of the drawn guides inside rect: the target's green outline and the forbidden strip's and
    the planned incision's magenta and violet (green or blue well above red's share of the tissue)."""
    w, h, data = pixels
    x0, y0, rw, rh = (int(round(v)) for v in rect)
    n = 0
    for y in range(max(0, y0), min(h, y0 + rh)):
        for x in range(max(0, x0), min(w, x0 + rw)):
            r, g, b = data[(y * w + x) * 3:(y * w + x) * 3 + 3]
            if (g > r + 60 and g > b + 30) or (b > g + 60 and r > g + 40):
                n += 1
    return n


def press(cdp, key, code, vk):
    for kind in ("keyDown", "keyUp"):
        cdp.call("Input.dispatchKeyEvent", type=kind, key=key, code=code, windowsVirtualKeyCode=vk,
                 **({"text": key} if kind == "keyDown" else {}))


def check_regions_key(cdp, outdir, shown_png):
    """G hides the regions and the planned incision (the guides' pixels in the trainee's view vanish)
    and shows them again, as on the desktop. The canvas takes the focus from a click beside the views."""
    views = json.loads(cdp.eval("document.body.dataset.views || '[]'") or "[]")
    x, y, w, h = views[0]
    for kind, buttons in (("mouseMoved", 0), ("mousePressed", 1), ("mouseReleased", 0)):
        extra = {} if kind == "mouseMoved" else {"button": "left", "buttons": buttons, "clickCount": 1}
        cdp.call("Input.dispatchMouseEvent", type=kind, x=5, y=y + h / 2, **extra)
    shown = guide_pixels(ppm_pixels(shown_png), views[0])
    press(cdp, "g", "KeyG", 71)
    time.sleep(1)
    off_png = os.path.join(outdir, "regions_off.png")
    cdp.screenshot(off_png)
    hidden = guide_pixels(ppm_pixels(off_png), views[0])
    press(cdp, "g", "KeyG", 71)
    time.sleep(1)
    back_png = os.path.join(outdir, "regions_on.png")
    cdp.screenshot(back_png)
    again = guide_pixels(ppm_pixels(back_png), views[0])
    print(f"web: G: guide pixels in the trainee's view {shown} shown, {hidden} after G, {again} after G again")
    if shown < 500 or hidden > shown // 10 or again < shown // 2:
        raise RuntimeError(f"G did not hide and show the regions: {shown}, {hidden}, {again} guide pixels")


def check_mouse(cdp, outdir):
    """Drives the default scene with the mouse and keyboard, as a trainee does, through DevTools' input
    events: a click on the side panel gives the canvas the focus, key 1 takes the forceps, a left drag
    from the trainee view's middle upwards grasps the tissue and lifts it. The page's `data-live`
    (instrument, grasp, elements moved, links cut) must show the forceps holding tissue that moved."""
    views = json.loads(cdp.eval("document.body.dataset.views || '[]'") or "[]")
    x, y, w, h = views[0]
    cx, cy = x + w / 2, y + h / 2

    def mouse(kind, px, py, **extra):
        cdp.call("Input.dispatchMouseEvent", type=kind, x=px, y=py, **extra)

    def live():
        return json.loads(cdp.eval("document.body.dataset.live || '{}'") or "{}")

    # Focus: a click outside the views (the panel beside them), where no instrument acts.
    mouse("mouseMoved", 5, y + h / 2)
    mouse("mousePressed", 5, y + h / 2, button="left", buttons=1, clickCount=1)
    mouse("mouseReleased", 5, y + h / 2, button="left", buttons=0, clickCount=1)
    for kind in ("keyDown", "keyUp"):
        cdp.call("Input.dispatchKeyEvent", type=kind, key="1", code="Digit1", windowsVirtualKeyCode=49,
                 **({"text": "1"} if kind == "keyDown" else {}))
    time.sleep(1)
    before = live()
    if before.get("instrument") != "Forceps":
        raise RuntimeError(f"mouse: key 1 did not take the forceps: the page says {before}")
    mouse("mouseMoved", cx, cy)
    time.sleep(0.3)
    mouse("mousePressed", cx, cy, button="left", buttons=1, clickCount=1)
    for k in range(1, 31):
        mouse("mouseMoved", cx, cy - 3 * k, button="left", buttons=1)
        time.sleep(0.05)
    time.sleep(1.5)
    during = live()
    cdp.screenshot(os.path.join(outdir, "mouse.png"))
    mouse("mouseReleased", cx, cy - 90, button="left", buttons=0, clickCount=1)
    moved = during.get("moved", 0) - before.get("moved", 0)
    print(f"web: mouse: forceps dragged 90 px up from the trainee view's middle: grasped "
          f"{during.get('grasped')}, {moved} element moves")
    if not during.get("grasped") or moved <= 0:
        raise RuntimeError(f"mouse: the forceps did not lift the tissue: before {before}, during {during}")


def main():
    url, outdir, native_metrics, broken, native_check = sys.argv[1:6]
    os.makedirs(outdir, exist_ok=True)
    chromium = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if not chromium:
        raise RuntimeError("no chromium on PATH")
    profile = tempfile.mkdtemp(prefix="dissect-chromium-")
    port = 9300 + os.getpid() % 500
    proc = subprocess.Popen(
        [chromium, "--headless=new", "--no-sandbox", "--disable-gpu-sandbox", f"--remote-debugging-port={port}",
         "--remote-debugging-address=127.0.0.1", f"--user-data-dir={profile}", "--window-size=1280,800",
         "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
         "--no-first-run", "--no-default-browser-check", "--disable-background-timer-throttling",
         "--disable-renderer-backgrounding", "about:blank"],
        stdout=subprocess.DEVNULL, stderr=open(os.path.join(outdir, "chromium.log"), "w"))
    try:
        targets = None
        for _ in range(150):
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=2) as r:
                    targets = [t for t in json.load(r) if t.get("type") == "page"]
                if targets:
                    break
            except OSError:
                pass
            time.sleep(0.2)
        if not targets:
            raise RuntimeError("Chromium's DevTools did not come up")
        cdp = Cdp(targets[0]["webSocketDebuggerUrl"])
        cdp.call("Page.enable")
        cdp.call("Runtime.enable")

        # 1. The default scene, both views.
        cdp.call("Page.navigate", url=url)
        first = float(cdp.wait_for("document.body && document.body.dataset.firstFrame", 60, "the first frame"))
        backend = cdp.eval("document.getElementById('backend').textContent")
        print(f"web: first frame {first:.0f} ms after navigation ({backend})")
        time.sleep(3)  # let the views settle and the steps-per-second figure fill in
        png = os.path.join(outdir, "default.png")
        cdp.screenshot(png)
        check_views(cdp, png, "default scene")
        time.sleep(2)
        stats = cdp.eval("document.getElementById('stats').textContent")
        print(f"web: default exercise: {stats}")
        if first > FIRST_FRAME_BUDGET_MS:
            raise RuntimeError(f"first frame after {first:.0f} ms, over the {FIRST_FRAME_BUDGET_MS} ms budget")

        # The regions and planned incision hidden and shown with G.
        check_regions_key(cdp, outdir, png)

        # 2. The instruments by hand: the mouse selects the forceps (key 1), grasps the tissue in the
        # middle of the trainee's view and drags it up; the tissue moves with it.
        check_mouse(cdp, outdir)

        # 3. The careful dissection played from the URL, against the native run.
        cdp.call("Page.navigate", url=url + "?scene=meninges&script=meninges_careful")
        # Its pace: the script's steps are due at the scene's rate, as a trainee's are, so the page's
        # steps per second while it plays (its grasps, lifts and strokes) is the browser's real time.
        cdp.wait_for("document.body && document.body.dataset.firstFrame", 60, "the script's first frame")
        started, paces = time.time(), []
        while not cdp.eval("document.body.dataset.done || ''") and time.time() - started < 300:
            time.sleep(0.5)
            stats = cdp.eval("document.getElementById('stats').textContent") or ""
            words = stats.split()
            if "steps/s" in words and time.time() - started > 1.5:
                paces.append(float(words[words.index("steps/s") - 1].replace(",", "")))
        played = time.time() - started
        cdp.wait_for("document.body && document.body.dataset.done", 300, "the script to finish")
        if paces:
            print(f"web: meninges_careful played in {played:.1f} s of wall time; the page's steps/s while it "
                  f"played: {min(paces):.0f} to {max(paces):.0f}")
        result = cdp.eval("document.getElementById('result').textContent")
        cdp.screenshot(os.path.join(outdir, "script.png"))
        if result.startswith("error"):
            raise RuntimeError(f"the script failed in the page: {result}")
        web = json.loads(result)
        with open(native_metrics) as f:
            native = json.load(f)
        ws, ns = web["assessment"]["score"], native["assessment"]["score"]
        print(f"web: meninges_careful: {web['steps']} steps, {web['links_cut']} links cut, score {ws:.2f} "
              f"(native: {native['steps']} steps, {native['links_cut']} links cut, score {ns:.2f}); "
              f"step mean {web['step_time_us']['mean']:.0f} us in the browser")
        if web["links_cut"] != native["links_cut"] or abs(ws - ns) > 0.1:
            raise RuntimeError("the browser's run differs from the native run")

        # 4. A broken scene through the file picker.
        cdp.call("Page.navigate", url=url)
        cdp.wait_for("document.body && document.body.dataset.firstFrame", 60, "the first frame")
        doc = cdp.call("DOM.getDocument")
        node = cdp.call("DOM.querySelector", nodeId=doc["root"]["nodeId"], selector="#file")["nodeId"]
        cdp.call("DOM.setFileInputFiles", nodeId=node, files=[os.path.abspath(broken)])
        shown = cdp.wait_for("document.getElementById('error').className == 'shown' && "
                             "document.getElementById('error').textContent", 30, "the scene's error")
        time.sleep(0.5)
        cdp.screenshot(os.path.join(outdir, "broken.png"))
        expected = native_check.strip()
        print(f"web: broken scene: the page shows {shown!r}")
        if expected not in shown:
            raise RuntimeError(f"the page's error {shown!r} is not native `dissect check`'s {expected!r}")
        print("web: all browser checks passed")
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
        shutil.rmtree(profile, ignore_errors=True)


if __name__ == "__main__":
    try:
        main()
    except RuntimeError as e:
        print(f"web: FAILED: {e}", file=sys.stderr)
        sys.exit(1)
