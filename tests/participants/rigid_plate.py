#!/usr/bin/env -S /usr/bin/python3
"""rigid_plate.py -- a replacement `structure` participant for sphfsi, written from docs/protocol.md alone.

A rigid rectangular plate (per metre of depth) that only translates vertically on a linear spring and damper:

    m y'' + c y' + k y = F_y(t),

F_y being the sum of the y-components of the vertex forces received in ADVANCE `inputs["force"]` (held constant
over each window).  Horizontal motion is constrained: every vertex has x displacement 0.

Run (Debian's interpreter, which has python3-zmq and python3-msgpack):

    SPHFSI_TOKEN=... /usr/bin/python3 rigid_plate.py --connect tcp://127.0.0.1:PORT --name structure [--token T]
    /usr/bin/python3 rigid_plate.py --self-test

`[structure]` configuration keys (validated here; anything wrong, unknown keys included, is ERROR `bad_config`):

    mass        kg per m depth, > 0, required
    stiffness   N/m per m, > 0, required
    damping     N s/m per m, >= 0, default 0
    x0, y0      lower-left corner of the plate in the reference configuration [m], default 0, 0
    width       [m], > 0, required
    thickness   [m], > 0, required
    cells       int >= 1, default 1: number of quads along the width in the interface mesh
    integrator  "exact" (default; exact solution of the ODE over each sub-step, force held constant)
                or "newmark" (average acceleration = trapezoidal rule)
    dt_max      [s], > 0, default period / 20 with period = 2 pi sqrt(m / k)
    y_initial   initial displacement [m], default 0
    v_initial   initial velocity [m/s], default 0

Interface mesh: vertices 0..cells on the bottom face (y = y0), vertices cells+1..2 cells+1 on the top face
(y = y0 + thickness), both left to right; cell i = [b_i, b_i+1, t_i+1, t_i] (counter-clockwise).

SNAPSHOT fields: `y`, `v`, `force_y` f8 [1, 1]; `energy` f8 [1, 3] = kinetic, spring potential (relative to
y = 0), work done by the external force since the start (exact for piecewise constant force: sum F dy).

Exit status: 0 after BYE; 2 bad command line; 3 refused by the coordinator (ERROR to HELLO, unusable WELCOME,
or no WELCOME within 30 s); 4 coordinator silent for timeout_s, also in the middle of a request; 130 SIGTERM or
SIGINT, also in the middle of a request (as the C++ participant runtime, protocol/src/participant.cpp).

The analytic SDOF responses `step_response` and `ramp_response` (for comparing coupled runs) need nothing but the
standard library; zmq and msgpack are only imported when the participant actually runs, so
`from rigid_plate import step_response` works anywhere.
"""

import collections
import math
import os
import signal
import struct
import sys
import threading
import time

SOFTWARE = "rigid_plate.py 1.0"
PROTOCOL_MIN = 1
PROTOCOL_MAX = 2                     # 2 adds interface_state to INIT and READY (the plate's state at t0)
MAX_MESSAGE_BYTES = 1 << 30          # docs/protocol.md section 1: 1 GiB
MAX_SUBSTEPS = 10_000_000            # our own bound on the work one ADVANCE may ask for
WELCOME_WAIT_S = 30.0                # how long to wait for WELCOME after HELLO (protocol does not say)
STATE_FORMAT = "rigid_plate/1"


# ---------------------------------------------------------------------------------------------------------------
# Analytic responses of m y'' + c y' + k y = f(t), from rest (y(0) = y'(0) = 0).  Written from the textbook formulas
# per damping case, independently of the integrators below, so that the self-test compares two derivations.
# ---------------------------------------------------------------------------------------------------------------

def _check_mck(m, c, k):
    if not (m > 0 and k > 0 and c >= 0):
        raise ValueError("need m > 0, k > 0, c >= 0")


def step_response(t, m, c, k, F):
    """Displacement y(t) of m y'' + c y' + k y = F H(t) from rest at t = 0 (y = 0 for t <= 0)."""
    _check_mck(m, c, k)
    if t <= 0.0:
        return 0.0
    w0 = math.sqrt(k / m)
    zeta = c / (2.0 * math.sqrt(k * m))
    ys = F / k
    if zeta < 1.0:
        wd = w0 * math.sqrt(1.0 - zeta * zeta)
        return ys * (1.0 - math.exp(-zeta * w0 * t)
                     * (math.cos(wd * t) + zeta / math.sqrt(1.0 - zeta * zeta) * math.sin(wd * t)))
    if zeta == 1.0:
        return ys * (1.0 - math.exp(-w0 * t) * (1.0 + w0 * t))
    r = math.sqrt(zeta * zeta - 1.0)
    s1 = -w0 * (zeta - r)            # slow root
    s2 = -w0 * (zeta + r)            # fast root
    return ys * (1.0 - (s2 * math.exp(s1 * t) - s1 * math.exp(s2 * t)) / (s2 - s1))


def _unbounded_ramp_response(t, m, c, k, rate):
    """y(t) for f(t) = rate * t (t >= 0), from rest."""
    if t <= 0.0:
        return 0.0
    w0 = math.sqrt(k / m)
    zeta = c / (2.0 * math.sqrt(k * m))
    a = rate / k
    # particular solution a (t - 2 zeta / w0); homogeneous part with u(0) = 2 a zeta / w0, u'(0) = -a
    u0 = 2.0 * a * zeta / w0
    v0 = -a
    if zeta < 1.0:
        wd = w0 * math.sqrt(1.0 - zeta * zeta)
        hom = math.exp(-zeta * w0 * t) * (u0 * math.cos(wd * t) + (v0 + zeta * w0 * u0) / wd * math.sin(wd * t))
    elif zeta == 1.0:
        hom = math.exp(-w0 * t) * (u0 + (v0 + w0 * u0) * t)
    else:
        r = math.sqrt(zeta * zeta - 1.0)
        s1 = -w0 * (zeta - r)
        s2 = -w0 * (zeta + r)
        A = (v0 - s2 * u0) / (s1 - s2)
        hom = A * math.exp(s1 * t) + (u0 - A) * math.exp(s2 * t)
    return a * (t - 2.0 * zeta / w0) + hom


def ramp_response(t, m, c, k, F, T):
    """Displacement y(t) for the force F t / T (0 <= t < T), then F (t >= T), from rest at t = 0.

    T <= 0 gives the step response."""
    _check_mck(m, c, k)
    if T <= 0.0:
        return step_response(t, m, c, k, F)
    rate = F / T
    y = _unbounded_ramp_response(t, m, c, k, rate)
    if t > T:
        y -= _unbounded_ramp_response(t - T, m, c, k, rate)
    return y


# ---------------------------------------------------------------------------------------------------------------
# Integrators: one sub-step of length h with the force F held constant.
# ---------------------------------------------------------------------------------------------------------------

def exact_step(y, v, F, h, m, c, k):
    """Exact solution of m y'' + c y' + k y = F over a step h (F constant), all damping cases.

    With u = y - F/k, sigma = c / 2m, w0^2 = k/m, the solution is
        u(h) = e^{-sigma h} [u0 C(h) + (v0 + sigma u0) S(h)]
        v(h) = e^{-sigma h} [v0 C(h) - (sigma v0 + w0^2 u0) S(h)]
    with C = cos(wd h), S = sin(wd h)/wd (under-damped, wd^2 = w0^2 - sigma^2 > 0), C = 1, S = h (critical),
    C = cosh(mu h), S = sinh(mu h)/mu (over-damped, mu^2 = sigma^2 - w0^2 > 0)."""
    if h == 0.0:
        return y, v
    sigma = c / (2.0 * m)
    w02 = k / m
    disc = c * c - 4.0 * k * m
    if disc < 0.0:
        wd = math.sqrt(-disc) / (2.0 * m)
        x = wd * h
        e = math.exp(-sigma * h)
        eC = e * math.cos(x)
        eS = e * (math.sin(x) / wd)
    elif disc == 0.0:
        e = math.exp(-sigma * h)
        eC = e
        eS = e * h
    else:
        mu = math.sqrt(disc) / (2.0 * m)
        x = mu * h
        if x < 1.0:
            e = math.exp(-sigma * h)
            eC = e * math.cosh(x)
            eS = e * (math.sinh(x) / mu)
        else:                                  # avoid overflow of cosh/sinh for long steps
            ep = math.exp((mu - sigma) * h)    # mu < sigma: decays
            em = math.exp(-(mu + sigma) * h)
            eC = 0.5 * (ep + em)
            eS = (ep - em) / (2.0 * mu)
    ys = F / k
    u0 = y - ys
    u1 = eC * u0 + eS * (v + sigma * u0)
    v1 = eC * v - eS * (sigma * v + w02 * u0)
    return u1 + ys, v1


def newmark_step(y, v, F, h, m, c, k):
    """Newmark average acceleration (beta = 1/4, gamma = 1/2), force F constant over the step.

    The start acceleration is taken from equilibrium with the same F, so for this linear ODE the scheme is the
    trapezoidal rule on (y, v); unconditionally stable, period error ~ (w h)^2 / 12."""
    a0 = (F - c * v - k * y) / m
    a1 = (F - c * (v + 0.5 * h * a0) - k * (y + h * v + 0.25 * h * h * a0)) / (m + 0.5 * c * h + 0.25 * k * h * h)
    y1 = y + h * v + 0.25 * h * h * (a0 + a1)
    v1 = v + 0.5 * h * (a0 + a1)
    return y1, v1


INTEGRATORS = {"exact": exact_step, "newmark": newmark_step}


# ---------------------------------------------------------------------------------------------------------------
# Configuration
# ---------------------------------------------------------------------------------------------------------------

class ConfigError(Exception):
    pass


def _is_number(x):
    return type(x) in (int, float) and math.isfinite(x)


CONFIG_KEYS = {
    # key: (required, default, description for messages)
    "mass": (True, None, "a number > 0 [kg per m]"),
    "stiffness": (True, None, "a number > 0 [N/m per m]"),
    "damping": (False, 0.0, "a number >= 0 [N s/m per m]"),
    "x0": (False, 0.0, "a finite number [m]"),
    "y0": (False, 0.0, "a finite number [m]"),
    "width": (True, None, "a number > 0 [m]"),
    "thickness": (True, None, "a number > 0 [m]"),
    "cells": (False, 1, "an integer >= 1 (at most 1000000)"),
    "integrator": (False, "exact", 'one of "exact", "newmark"'),
    "dt_max": (False, None, "a number > 0 [s] (default: period / 20)"),
    "y_initial": (False, 0.0, "a finite number [m]"),
    "v_initial": (False, 0.0, "a finite number [m/s]"),
}


def parse_config(cfg):
    """Validate the INIT `config` map; return a dict of parameters or raise ConfigError naming key and range."""
    if not isinstance(cfg, dict):
        raise ConfigError("structure config must be a map of the keys %s" % ", ".join(sorted(CONFIG_KEYS)))
    for key in cfg:
        if key not in CONFIG_KEYS:
            raise ConfigError("structure.%s is not a known key; allowed keys: %s"
                              % (key if isinstance(key, str) else repr(key), ", ".join(sorted(CONFIG_KEYS))))
    p = {}
    for key, (required, default, allowed) in CONFIG_KEYS.items():
        if key not in cfg:
            if required:
                raise ConfigError("structure.%s is required: %s" % (key, allowed))
            p[key] = default
            continue
        val = cfg[key]
        bad = ConfigError("structure.%s = %r is invalid: must be %s" % (key, val, allowed))
        if key == "integrator":
            if not isinstance(val, str) or val not in INTEGRATORS:
                raise bad
            p[key] = val
        elif key == "cells":
            if type(val) is not int or val < 1 or val > 1000000:
                raise bad
            p[key] = val
        else:
            if not _is_number(val):
                raise bad
            val = float(val)
            if key in ("mass", "stiffness", "width", "thickness", "dt_max") and not val > 0.0:
                raise bad
            if key == "damping" and not val >= 0.0:
                raise bad
            p[key] = val
    m, k = p["mass"], p["stiffness"]
    p["period"] = 2.0 * math.pi * math.sqrt(m / k)
    if not (math.isfinite(p["period"]) and p["period"] > 0.0):
        raise ConfigError("structure.mass / structure.stiffness = %r gives no finite period > 0" % (m / k))
    if p["dt_max"] is None:
        p["dt_max"] = p["period"] / 20.0
    return p


# ---------------------------------------------------------------------------------------------------------------
# The plate model
# ---------------------------------------------------------------------------------------------------------------

class Plate:
    def __init__(self, p, t0):
        self.p = p
        self.m, self.c, self.k = p["mass"], p["damping"], p["stiffness"]
        self.step = INTEGRATORS[p["integrator"]]
        self.t = float(t0)
        self.y = p["y_initial"]
        self.v = p["v_initial"]
        self.work = 0.0
        self.force_y = 0.0
        self.saved = None
        n = p["cells"]
        x0, y0, w, th = p["x0"], p["y0"], p["width"], p["thickness"]
        xs = [x0 + w * i / n for i in range(n + 1)]
        xs[-1] = x0 + w
        self.vertices = [(x, y0) for x in xs] + [(x, y0 + th) for x in xs]
        self.cells = [(i, i + 1, n + 2 + i, n + 1 + i) for i in range(n)]
        self.n_vertices = len(self.vertices)

    # state for SAVE/RESTORE and CHECKPOINT
    def core(self):
        return {"t": self.t, "y": self.y, "v": self.v, "work": self.work, "force_y": self.force_y}

    def set_core(self, s):
        self.t, self.y, self.v, self.work, self.force_y = s["t"], s["y"], s["v"], s["work"], s["force_y"]

    def energy(self):
        return (0.5 * self.m * self.v * self.v, 0.5 * self.k * self.y * self.y, self.work)

    def advance(self, F, dt, n, on_substep):
        """Advance n equal sub-steps over dt with the force F.  Returns None, or an error sentence (diverged);
        on error the state is left at the window start."""
        start = self.core()
        h = dt / n
        y, v, work = self.y, self.v, self.work
        for i in range(n):
            y1, v1 = self.step(y, v, F, h, self.m, self.c, self.k)
            if not (math.isfinite(y1) and math.isfinite(v1)):
                self.set_core(start)
                return ("sub-step %d of %d at t = %.17g: plate displacement y = %r, velocity v = %r is not finite"
                        % (i + 1, n, start["t"] + (i + 1) * h, y1, v1))
            work += F * (y1 - y)
            y, v = y1, v1
            on_substep()
        self.y, self.v, self.work, self.force_y = y, v, work, F
        return None


# ---------------------------------------------------------------------------------------------------------------
# Wire format helpers
# ---------------------------------------------------------------------------------------------------------------

class ProtocolError(Exception):
    def __init__(self, code, message):
        Exception.__init__(self, message)
        self.code = code
        self.message = message


def bad(message):
    return ProtocolError("bad_message", message)


def f8_array(values, shape):
    values = [float(x) for x in values]
    return {"dtype": "f8", "shape": list(shape), "data": struct.pack("<%dd" % len(values), *values)}


def i4_array(values, shape):
    return {"dtype": "i4", "shape": list(shape), "data": struct.pack("<%di" % len(values), *values)}


def decode_array(a, where):
    """Validate an array map (section 2.1); return (dtype, shape, tuple of values)."""
    if not isinstance(a, dict):
        raise bad("%s is not an array map" % where)
    if set(a) != {"dtype", "shape", "data"}:
        raise bad("%s must have exactly the keys dtype, shape, data (has %s)"
                  % (where, ", ".join(sorted(map(str, a)))))
    dtype, shape, data = a["dtype"], a["shape"], a["data"]
    if dtype not in ("f8", "i4") or not isinstance(dtype, str):
        raise bad("%s.dtype must be \"f8\" or \"i4\"" % where)
    if (not isinstance(shape, list) or not 1 <= len(shape) <= 4
            or any(type(s) is not int or s < 0 for s in shape)):
        raise bad("%s.shape must be an array of 1 to 4 non-negative ints" % where)
    if not isinstance(data, bytes):
        raise bad("%s.data must be bin" % where)
    count = 1
    for s in shape:
        count *= s
    itemsize = 8 if dtype == "f8" else 4
    if len(data) != count * itemsize:
        raise bad("%s.data has %d bytes, shape %s of %s needs %d" % (where, len(data), shape, dtype, count * itemsize))
    values = struct.unpack("<%d%s" % (count, "d" if dtype == "f8" else "i"), data)
    return dtype, shape, values


def _int(x, where, minimum=None):
    if type(x) is not int:
        raise bad("%s must be an int" % where)
    if minimum is not None and x < minimum:
        raise bad("%s must be >= %d" % (where, minimum))
    return x


def _float(x, where, positive=False):
    if type(x) not in (int, float) or not math.isfinite(x):
        raise bad("%s must be a finite float" % where)
    x = float(x)
    if positive and not x > 0.0:
        raise bad("%s must be > 0" % where)
    return x


def check_keys(body, keys, type_):
    got = set(body)
    missing = [k for k in keys if k not in got]
    extra = sorted(str(k) for k in got if k not in keys)
    if missing or extra:
        parts = []
        if missing:
            parts.append("missing " + ", ".join(missing))
        if extra:
            parts.append("unknown " + ", ".join(extra))
        raise bad("%s body: %s" % (type_, "; ".join(parts)))


ENVELOPE_KEYS = ("v", "type", "seq", "token", "body")
MESSAGE_TYPES = {"HELLO", "WELCOME", "INIT", "READY", "ADVANCE", "ADVANCED", "SAVE", "RESTORE", "SNAPSHOT", "FRAME",
                 "CHECKPOINT", "STATE", "ACK", "HEARTBEAT", "BYE", "ERROR"}
REQUESTS = {"INIT", "ADVANCE", "SAVE", "RESTORE", "SNAPSHOT", "CHECKPOINT", "BYE"}


def log(msg):
    try:
        sys.stderr.write("rigid_plate: %s\n" % msg)
        sys.stderr.flush()
    except Exception:
        pass


# ---------------------------------------------------------------------------------------------------------------
# The participant
# ---------------------------------------------------------------------------------------------------------------

class Exit(Exception):
    def __init__(self, status):
        Exception.__init__(self, status)
        self.status = status


class Participant:
    def __init__(self, endpoint, name, token):
        import msgpack
        import zmq
        self.zmq = zmq
        self.msgpack = msgpack
        self.name = name
        self.token = token
        self.ctx = zmq.Context()
        self.sock = self.ctx.socket(zmq.DEALER)
        self.sock.setsockopt(zmq.LINGER, 2000)
        self.sock.setsockopt(zmq.SNDTIMEO, 5000)
        self.sock.connect(endpoint)
        self.lock = threading.Lock()         # guards the socket and self.seq
        self.seq = 0                         # our own counter: HELLO and HEARTBEAT
        self.version = None                  # the session's version once welcomed
        self.state = "CONNECTING"
        self.heartbeat_s = 0.5
        self.timeout_s = 3.0
        self.progress = 0
        self.hello_seq = None
        self.plate = None
        self.params = None
        self.stop = threading.Event()
        self.hb_thread = None
        # While the main thread handles a request (`computing`), the heartbeat thread takes what arrives:
        # a well-formed coordinator HEARTBEAT refreshes `last_heard`, anything else waits in `pending`, in
        # arrival order, and recv() returns `pending` before reading the socket. Both change under
        # self.lock, as every socket use, so nothing is lost or reordered (see _heartbeat_loop).
        self.computing = False
        self.pending = collections.deque()
        self.last_heard = time.monotonic()

    # -- sending -----------------------------------------------------------------------------------------------
    def _next_seq(self):
        self.seq += 1
        return self.seq

    def _pack(self, type_, seq, body):
        v = self.version if self.version is not None else PROTOCOL_MAX
        return self.msgpack.packb({"v": v, "type": type_, "seq": seq, "token": self.token, "body": body},
                                  use_bin_type=True)

    def send(self, type_, seq, body):
        """Send a reply (seq = the request's) or a request (seq None: next own number)."""
        with self.lock:
            if seq is None:
                seq = self._next_seq()
            frame = self._pack(type_, seq, body)
            try:
                self.sock.send(frame)
            except self.zmq.Again:
                log("could not send %s for 5 s; the coordinator is gone" % type_)
                raise Exit(4)
        return seq

    def send_error(self, code, message, in_reply_to):
        log("ERROR %s (in reply to seq %d): %s" % (code, in_reply_to, message))
        body = {"code": code, "message": message, "in_reply_to": in_reply_to}
        self.send("ERROR", in_reply_to, body)  # a reply carries the seq it answers; 0 if that was unreadable

    def _is_plain_heartbeat(self, frames):
        """Whether the main loop would drop these frames silently: a well-formed HEARTBEAT of this session."""
        if len(frames) != 1:
            return False
        try:
            env = self.msgpack.unpackb(frames[0], raw=False, strict_map_key=True)
        except Exception:
            return False
        return (isinstance(env, dict) and set(env) == set(ENVELOPE_KEYS) and env["type"] == "HEARTBEAT"
                and env["v"] == self.version and env["token"] == self.token
                and type(env["seq"]) is int and env["seq"] >= 0 and isinstance(env["body"], dict)
                and set(env["body"]) == {"progress"} and type(env["body"]["progress"]) is int)

    def _heartbeat_loop(self):
        # While the main thread computes (an ADVANCE may take many seconds) it reads nothing, so this thread
        # takes the arriving messages and ends the process (os._exit: the computation cannot be stopped, and
        # its result has nobody to go to) when the coordinator has been silent for more than timeout_s, as
        # the C++ runtime does. Between requests the main loop checks the silence itself.
        period = max(0.001, 0.5 * self.heartbeat_s)
        while True:
            with self.lock:
                if self.stop.is_set():
                    return
                if self.computing:
                    while self.sock.poll(0, self.zmq.POLLIN):
                        frames = self.sock.recv_multipart(self.zmq.NOBLOCK)
                        self.last_heard = time.monotonic()
                        if not self._is_plain_heartbeat(frames):
                            self.pending.append(frames)
                    silent = time.monotonic() - self.last_heard
                    if silent > self.timeout_s:
                        log("heard nothing from the coordinator for %.3g s while computing; exiting" % silent)
                        os._exit(4)
                try:
                    self.sock.send(self._pack("HEARTBEAT", self._next_seq(), {"progress": self.progress}),
                                   self.zmq.NOBLOCK)
                except self.zmq.Again:
                    pass
                except self.zmq.ZMQError as e:
                    log("heartbeat send failed: %s" % e)
                    return
            if self.stop.wait(period):
                return

    # -- receiving -----------------------------------------------------------------------------------------------
    def recv(self, timeout_s):
        """Return the frames of one message, or None after timeout_s of silence."""
        deadline = time.monotonic() + timeout_s
        slice_ms = max(1, min(20, int(self.heartbeat_s * 250)))
        while True:
            with self.lock:
                if self.pending:
                    return self.pending.popleft()
                if self.sock.poll(slice_ms, self.zmq.POLLIN):
                    self.last_heard = time.monotonic()
                    return self.sock.recv_multipart(self.zmq.NOBLOCK)
            if time.monotonic() >= deadline:
                return None
            time.sleep(0.001)        # let the heartbeat thread take the lock

    def run(self):
        self.hello_seq = self.send("HELLO", None, {
            "name": self.name, "kind": "structure", "version_min": PROTOCOL_MIN, "version_max": PROTOCOL_MAX,
            "software": SOFTWARE, "pid": os.getpid()})
        try:
            while True:
                wait = WELCOME_WAIT_S if self.state == "CONNECTING" else self.timeout_s
                frames = self.recv(wait)
                if frames is None:
                    if self.state == "CONNECTING":
                        log("no WELCOME within %g s; giving up" % wait)
                        raise Exit(3)
                    log("heard nothing from the coordinator for %g s; exiting" % wait)
                    raise Exit(4)
                with self.lock:
                    self.computing = True
                try:
                    self.handle(frames)
                finally:
                    with self.lock:
                        self.computing = False
        except Exit as e:
            self.close(linger_ms=2000 if e.status == 0 else 0)
            return e.status

    def close(self, linger_ms):
        self.stop.set()
        if self.hb_thread is not None:
            self.hb_thread.join(timeout=2.0)
        with self.lock:
            self.sock.close(linger=linger_ms)
        self.ctx.term()

    # -- dispatch -------------------------------------------------------------------------------------------------
    def handle(self, frames):
        seq, type_ = 0, None
        try:
            if len(frames) != 1:
                raise bad("a message must be one frame, got %d" % len(frames))
            frame = frames[0]
            if len(frame) > MAX_MESSAGE_BYTES:
                raise ProtocolError("too_large", "message of %d bytes exceeds the limit of %d"
                                    % (len(frame), MAX_MESSAGE_BYTES))
            try:
                env = self.msgpack.unpackb(frame, raw=False, strict_map_key=True)
            except Exception as e:
                detail = str(e)[:200]
                raise bad("not a valid MessagePack message (%s%s)" % (type(e).__name__, ": " + detail if detail
                                                                       else ""))
            if not isinstance(env, dict):
                raise bad("the envelope must be a map, got %s" % type(env).__name__)
            s = env.get("seq")
            if type(s) is int and s >= 0:
                seq = s
            type_ = env.get("type")
            check_keys(env, ENVELOPE_KEYS, "envelope")
            v = env["v"]
            if type(v) is not int or v < 1:
                raise bad("envelope v must be a positive int")
            if not isinstance(type_, str):
                raise bad("envelope type must be a str")
            if type(s) is not int or s < 0:
                raise bad("envelope seq must be a non-negative int")
            if not isinstance(env["token"], str):
                raise bad("envelope token must be a str")
            body = env["body"]
            if not isinstance(body, dict):
                raise bad("envelope body must be a map")
        except ProtocolError as e:
            if type_ in ("HEARTBEAT", "ERROR"):  # not requests: a malformed one is logged, never answered
                log("ignoring a malformed %s: %s" % (type_, e.message))
            else:
                self.send_error(e.code, e.message, seq)
            return

        if type_ == "HEARTBEAT":             # never answered, even when wrong
            problem = None
            if self.version is not None and v != self.version:
                problem = "version %d, session is %d" % (v, self.version)
            elif env["token"] != self.token:
                problem = "wrong token"
            elif set(body) != {"progress"} or type(body["progress"]) is not int:
                problem = "body must be {progress: int}"
            if problem:
                log("ignoring a malformed HEARTBEAT (seq %d): %s" % (seq, problem))
            return

        if type_ == "ERROR" and self.state == "CONNECTING":
            # the refusal of our HELLO: it may be in another version (version_mismatch) or carry the
            # coordinator's token (bad_token), so take it as it comes
            log("the coordinator refused us: %r" % (body,))
            raise Exit(3)
        if type_ == "ERROR":  # not a request: logged and never answered, whatever its version or token
            log("the coordinator sent ERROR (seq %d): %r" % (seq, body))
            return

        try:
            if self.version is not None:
                if v != self.version:
                    raise ProtocolError("version_mismatch", "message in protocol version %d, the session speaks %d"
                                        % (v, self.version))
            elif not PROTOCOL_MIN <= v <= PROTOCOL_MAX:
                raise ProtocolError("version_mismatch", "message in protocol version %d, this participant speaks "
                                    "%d..%d" % (v, PROTOCOL_MIN, PROTOCOL_MAX))
            if env["token"] != self.token:
                raise ProtocolError("bad_token", "the token is not this run's")
            if type_ not in MESSAGE_TYPES:
                raise ProtocolError("unknown_type", "%r is not a message type of protocol version %d"
                                    % (type_[:40], v))
            if type_ == "WELCOME":
                self.on_welcome(seq, body)
                return
            if type_ not in REQUESTS:
                raise ProtocolError("bad_state", "a participant never receives %s" % type_)
            if self.state == "CONNECTING":
                raise ProtocolError("bad_state", "%s before WELCOME" % type_)
            if type_ == "BYE":
                check_keys(body, (), type_)
                self.send("ACK", seq, {})
                self.state = "CLOSED"
                raise Exit(0)
            if type_ == "INIT":
                if self.state != "WELCOMED":
                    raise ProtocolError("bad_state", "INIT after a successful INIT")
                self.on_init(seq, body)
                return
            if self.state != "READY":
                raise ProtocolError("bad_state", "%s before a successful INIT" % type_)
            getattr(self, "on_" + type_.lower())(seq, body)
        except ProtocolError as e:
            self.send_error(e.code, e.message, seq)
        except Exit:
            raise
        except Exception as e:                     # a bug of ours: report, keep running
            self.send_error("internal", "%s while handling %s: %s" % (type(e).__name__, type_, e), seq)

    # -- handlers ---------------------------------------------------------------------------------------------------
    def on_welcome(self, seq, body):
        if self.state != "CONNECTING":
            raise ProtocolError("bad_state", "WELCOME when already welcomed")
        try:
            check_keys(body, ("version", "heartbeat_s", "timeout_s"), "WELCOME")
            version = _int(body["version"], "WELCOME version", 1)
            hb = _float(body["heartbeat_s"], "WELCOME heartbeat_s", positive=True)
            to = _float(body["timeout_s"], "WELCOME timeout_s", positive=True)
            if not PROTOCOL_MIN <= version <= PROTOCOL_MAX:
                raise ProtocolError("version_mismatch", "WELCOME chose version %d, this participant speaks %d..%d"
                                    % (version, PROTOCOL_MIN, PROTOCOL_MAX))
        except ProtocolError as e:
            self.send_error(e.code, e.message, seq)
            raise Exit(3)
        if seq != self.hello_seq:
            log("WELCOME carries seq %d, HELLO had %d; accepting it" % (seq, self.hello_seq))
        self.version, self.heartbeat_s, self.timeout_s = version, hb, to
        self.state = "WELCOMED"
        self.hb_thread = threading.Thread(target=self._heartbeat_loop, name="heartbeat", daemon=True)
        self.hb_thread.start()

    def on_init(self, seq, body):
        keys = ("config", "t0", "interface", "state") + (("interface_state",) if self.version >= 2 else ())
        check_keys(body, keys, "INIT")
        if self.version >= 2 and body["interface_state"] != {}:
            raise bad("INIT interface_state must be empty for a structure")
        t0 = _float(body["t0"], "INIT t0")
        if body["interface"] is not None:
            raise bad("INIT interface must be nil for a structure")
        state = body["state"]
        if not isinstance(state, bytes):
            raise bad("INIT state must be bin")
        try:
            p = parse_config(body["config"])
        except ConfigError as e:
            raise ProtocolError("bad_config", str(e))
        plate = Plate(p, t0)
        if state:
            self.restore_checkpoint(plate, state, t0)
        self.plate, self.params = plate, p
        n = plate.n_vertices
        mesh = {"vertices": f8_array([c for xy in plate.vertices for c in xy], (n, 2)),
                "cells": i4_array([i for cell in plate.cells for i in cell], (len(plate.cells), 4))}
        zeta = p["damping"] / (2.0 * math.sqrt(p["mass"] * p["stiffness"]))
        info = {"vertices": n, "cells": len(plate.cells), "period_s": p["period"], "damping_ratio": zeta,
                "dt_max_s": p["dt_max"], "resumed": 1 if state else 0}
        ready = {"dt_wanted": p["dt_max"], "interface": mesh, "info": info}
        if self.version >= 2:
            # Every vertex moves with the plate: y_initial / v_initial (or a resumed state) at t0, so the
            # coordinator's watchpoints and a fluid see the plate where it is from the start.
            moving = plate.y != 0.0 or plate.v != 0.0
            ready["interface_state"] = {
                "displacement": f8_array([0.0, plate.y] * n, (n, 2)),
                "velocity": f8_array([0.0, plate.v] * n, (n, 2))} if moving else {}
        self.send("READY", seq, ready)
        self.state = "READY"

    def restore_checkpoint(self, plate, state, t0):
        try:
            s = self.msgpack.unpackb(state, raw=False)
            ok = (isinstance(s, dict) and s.get("format") == STATE_FORMAT
                  and isinstance(s.get("core"), dict) and set(s["core"]) == set(plate.core())
                  and all(type(x) is float and math.isfinite(x) for x in s["core"].values())
                  and (s.get("saved") is None or (isinstance(s["saved"], dict)
                                                  and set(s["saved"]) == set(plate.core())))
                  and type(s.get("progress")) is int)
        except Exception:
            ok = False
        if not ok:
            # docs/protocol.md, INIT: a state the participant cannot use is bad_config (it was bad_message here)
            raise ProtocolError("bad_config", "INIT state is not a %s checkpoint of this program" % STATE_FORMAT)
        if abs(s["core"]["t"] - t0) > 1e-9 * abs(t0):  # docs/protocol.md, INIT: one instant, or refused
            raise ProtocolError("bad_config", "INIT t0 = %.17g but the checkpoint is at t = %.17g" % (t0, s["core"]["t"]))
        plate.set_core(s["core"])
        plate.saved = s["saved"]
        self.progress = s["progress"]
        if s.get("params") != {k: v for k, v in plate.p.items()}:
            log("warning: the configuration differs from the one the checkpoint was written with")

    def on_advance(self, seq, body):
        t0 = time.perf_counter()
        check_keys(body, ("t", "dt", "substeps", "iteration", "inputs"), "ADVANCE")
        t = _float(body["t"], "ADVANCE t")
        dt = _float(body["dt"], "ADVANCE dt", positive=True)
        substeps = _int(body["substeps"], "ADVANCE substeps", 0)
        _int(body["iteration"], "ADVANCE iteration", 0)
        inputs = body["inputs"]
        if not isinstance(inputs, dict):
            raise bad("ADVANCE inputs must be a map of arrays")
        plate = self.plate
        n = plate.n_vertices
        # The coordinator always sends exactly `force` (docs/protocol.md, ADVANCE): anything else means the two
        # sides disagree about the run.
        if "force" not in inputs:
            raise bad("ADVANCE inputs lack the field 'force' (a structure takes exactly: force)")
        extra = [str(k) for k in inputs if k != "force"]
        if extra:
            raise bad("ADVANCE inputs: unknown field(s) %s; a structure takes only force" % ", ".join(sorted(extra)))
        dtype, shape, values = decode_array(inputs["force"], "inputs.force")
        if dtype != "f8" or shape != [n, 2]:
            raise bad("inputs.force must be f8 [%d, 2], got %s %s" % (n, dtype, shape))
        if not all(math.isfinite(x) for x in values):
            raise bad("inputs.force holds a value that is not finite")
        F = math.fsum(values[1::2])
        tol = 1e-9 * max(abs(plate.t), dt)
        if abs(t - plate.t) > tol:
            raise ProtocolError("bad_state", "ADVANCE t = %.17g but the plate is at t = %.17g" % (t, plate.t))
        if substeps == 0:
            nsub = max(1, math.ceil(dt / self.params["dt_max"] * (1.0 - 1e-12)))
            nsub = min(nsub, MAX_SUBSTEPS)
        else:
            nsub = substeps
            if nsub > MAX_SUBSTEPS:
                raise bad("ADVANCE substeps = %d exceeds this participant's limit of %d" % (nsub, MAX_SUBSTEPS))

        def tick():
            self.progress += 1

        err = plate.advance(F, dt, nsub, tick)
        if err is not None:
            raise ProtocolError("diverged", err)
        plate.t = t + dt
        y, v = plate.y, plate.v
        out = {"displacement": f8_array([0.0, y] * n, (n, 2)), "velocity": f8_array([0.0, v] * n, (n, 2))}
        self.send("ADVANCED", seq, {
            "t": plate.t, "dt_wanted": self.params["dt_max"], "outputs": out, "substeps": nsub,
            "solver_iterations": 0, "compute_s": time.perf_counter() - t0,
            "stats": {"y": y, "v": v, "force_y": F}})

    def on_save(self, seq, body):
        check_keys(body, (), "SAVE")
        self.plate.saved = self.plate.core()
        self.send("ACK", seq, {})

    def on_restore(self, seq, body):
        check_keys(body, (), "RESTORE")
        if self.plate.saved is None:
            raise ProtocolError("bad_state", "RESTORE without an earlier SAVE")
        self.plate.set_core(self.plate.saved)
        self.send("ACK", seq, {})

    def on_snapshot(self, seq, body):
        check_keys(body, (), "SNAPSHOT")
        pl = self.plate
        self.send("FRAME", seq, {"t": pl.t, "fields": {
            "y": f8_array([pl.y], (1, 1)), "v": f8_array([pl.v], (1, 1)),
            "force_y": f8_array([pl.force_y], (1, 1)), "energy": f8_array(pl.energy(), (1, 3))}})

    def on_checkpoint(self, seq, body):
        check_keys(body, (), "CHECKPOINT")
        pl = self.plate
        blob = self.msgpack.packb({"format": STATE_FORMAT, "core": pl.core(), "saved": pl.saved,
                                   "progress": self.progress, "params": dict(pl.p)}, use_bin_type=True)
        self.send("STATE", seq, {"t": pl.t, "state": blob})


# ---------------------------------------------------------------------------------------------------------------
# Self-test of the integrators against the analytic responses
# ---------------------------------------------------------------------------------------------------------------

def _integrate(step, m, c, k, force_of_t, t_end, h):
    """Integrate from rest with a per-step force force_of_t(t_start, t_end); return the max |y - y_exact| list."""
    n = int(round(t_end / h))
    y = v = 0.0
    ys = []
    for i in range(n):
        ta, tb = i * h, (i + 1) * h
        y, v = step(y, v, force_of_t(ta, tb), h, m, c, k)
        ys.append((tb, y))
    return ys


def self_test():
    ok = True
    m, k, F = 2.0, 50.0, 3.0
    w0 = math.sqrt(k / m)
    period = 2.0 * math.pi / w0
    ystat = F / k
    print("SDOF m = %g, k = %g, F = %g: w0 = %g rad/s, period = %g s, F/k = %g" % (m, k, F, w0, period, ystat))

    # 1) exact integrator vs the analytic step response, all damping cases, several step sizes
    worst = 0.0
    for zeta in (0.0, 0.05, 0.7, 1.0, 1.0 + 1e-9, 2.5):
        c = 2.0 * zeta * math.sqrt(k * m)
        for h in (period / 20.0, period / 7.3, 0.37 * period):
            hist = _integrate(exact_step, m, c, k, lambda a, b: F, 10.0 * period, h)
            err = max(abs(y - step_response(t, m, c, k, F)) for t, y in hist) / ystat
            worst = max(worst, err)
            print("  exact   step  zeta=%-12.10g h=T/%-6.3g max |error| / (F/k) = %.3e" % (zeta, period / h, err))
    print("exact integrator vs analytic step response: max relative error %.3e" % worst)
    ok &= worst < 1e-11

    # 2) Newmark (average acceleration) vs the analytic step response, undamped: the phase error after time t is
    #    w0 t (w0 h)^2 / 12, so the error amplitude is about (F/k) w0 t (w0 h)^2 / 12 (while that is small)
    t_end = 2.0 * period
    print("newmark vs analytic step response (undamped, %g periods):" % (t_end / period))
    ratios = []
    for div in (20, 40, 80, 160):
        h = period / div
        hist = _integrate(newmark_step, m, 0.0, k, lambda a, b: F, t_end, h)
        err = max(abs(y - step_response(t, m, 0.0, k, F)) for t, y in hist) / ystat
        predicted = w0 * t_end * (w0 * h) ** 2 / 12.0
        ratios.append(err / predicted)
        print("  newmark step  h=T/%-4d (w h)^2=%.4f max |error| / (F/k) = %.3e   predicted %.3e   ratio %.3f"
              % (div, (w0 * h) ** 2, err, predicted, err / predicted))
    ok &= all(0.8 < r < 1.2 for r in ratios)

    # 3) the analytic ramp response vs the exact integrator with the ramp's average force over each (short) step:
    #    second order in h; and a check that the analytic ramp satisfies the ODE (finite differences)
    for zeta in (0.0, 0.1, 1.0, 3.0):
        c = 2.0 * zeta * math.sqrt(k * m)
        T = 1.3 * period
        ramp = lambda t: F * min(t, T) / T

        def avg(a, b):
            # exact average of the ramp over [a, b]
            if b <= T:
                return 0.5 * (ramp(a) + ramp(b))
            if a >= T:
                return F
            return ((b - T) * F + (T - a) * 0.5 * (ramp(a) + F)) / (b - a)
        errs = []
        for div in (50, 100):
            h = period / div
            hist = _integrate(exact_step, m, c, k, avg, 4.0 * period, h)
            errs.append(max(abs(y - ramp_response(t, m, c, k, F, T)) for t, y in hist) / ystat)
        order = math.log(errs[0] / errs[1], 2.0) if errs[1] > 0 else float("inf")
        d = 1e-4 * period
        res = 0.0
        for i in range(1, 200):
            t = 4.0 * period * i / 200.0
            if abs(t - T) < 3 * d:
                continue
            yp, y0_, ym = (ramp_response(t + d, m, c, k, F, T), ramp_response(t, m, c, k, F, T),
                           ramp_response(t - d, m, c, k, F, T))
            r = m * (yp - 2 * y0_ + ym) / d ** 2 + c * (yp - ym) / (2 * d) + k * y0_ - ramp(t)
            res = max(res, abs(r) / F)
        print("  ramp    zeta=%-4g exact integrator (ramp averaged per step) vs analytic: h=T/50 %.2e, h=T/100 %.2e"
              " (order %.2f); ODE residual / F = %.1e" % (zeta, errs[0], errs[1], order, res))
        ok &= 1.8 < order < 2.2 and res < 1e-4
    # continuity of the ramp response at T and its long-time limit
    c = 2.0 * 0.3 * math.sqrt(k * m)
    T = 0.8 * period
    jump = abs(ramp_response(T * (1 + 1e-12), m, c, k, F, T) - ramp_response(T * (1 - 1e-12), m, c, k, F, T))
    late = abs(ramp_response(200.0 * period, m, c, k, F, T) - ystat) / ystat
    print("  ramp continuity at T: jump %.1e; y(200 T)/ (F/k) - 1 = %.1e" % (jump, late))
    ok &= jump < 1e-10 and late < 1e-9

    # 4) the plate model: SAVE/RESTORE and sub-stepping reproduce bit for bit
    p = parse_config({"mass": m, "stiffness": k, "damping": 0.3, "width": 1.0, "thickness": 0.1, "cells": 3})
    a, b = Plate(p, 0.0), Plate(p, 0.0)
    a.advance(F, 0.1, 4, lambda: None)
    saved = a.core()
    a.advance(2 * F, 0.1, 4, lambda: None)
    a.set_core(saved)
    a.advance(F, 0.1, 4, lambda: None)
    b.advance(F, 0.1, 4, lambda: None)
    b.advance(F, 0.1, 4, lambda: None)
    same = a.core() == b.core()
    print("  plate SAVE/RESTORE reproduces exactly: %s" % same)
    ok &= same
    try:
        parse_config({"mass": 1.0, "stiffness": 1.0, "width": 1.0, "thickness": 1.0, "colour": "red"})
        ok = False
    except ConfigError as e:
        print("  unknown key refused: %s" % e)
    print("self-test %s" % ("PASSED" if ok else "FAILED"))
    return 0 if ok else 1


# ---------------------------------------------------------------------------------------------------------------

def main(argv):
    import argparse
    ap = argparse.ArgumentParser(description="rigid plate on a spring: an sphfsi structure participant")
    ap.add_argument("--connect", help="coordinator endpoint, e.g. tcp://127.0.0.1:5555")
    ap.add_argument("--name", help="the role (normally structure)")
    ap.add_argument("--token", help="the run token (default: $SPHFSI_TOKEN)")
    ap.add_argument("--self-test", action="store_true", help="check the integrators against the analytic solution")
    args = ap.parse_args(argv)
    if args.self_test:
        return self_test()
    if not args.connect or not args.name:
        ap.error("--connect and --name are required")
    token = args.token if args.token is not None else os.environ.get("SPHFSI_TOKEN")
    if not token:
        ap.error("no token: pass --token or set SPHFSI_TOKEN")
    def on_signal(signum, frame):
        # The handler runs in the main thread between bytecodes, so also in the middle of an ADVANCE: exit at
        # once with the C++ runtime's status (the launcher's parent-death signal is SIGTERM).
        log("stopped by signal %d; exiting" % signum)
        os._exit(130)
    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    try:
        participant = Participant(args.connect, args.name, token)
    except Exception as e:
        log("cannot connect to %s: %s" % (args.connect, e))
        return 2
    return participant.run()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
