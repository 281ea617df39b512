"""The reference participant runtime (protocol/src/participant.cpp) keeps the rules of docs/protocol.md,
§3 "Rules": this test plays the coordinator by hand against a real sphfsi-structure (and sphfsi-fluid) over
127.0.0.1 and checks the answers a replacement solver's author would rely on. The checks that hold for any
structure participant run against tests/participants/rigid_plate.py too, which must behave the same.
Every wait is bounded."""
import os
import signal
import struct
import subprocess
import tempfile
import time
import tomllib

import msgpack
import zmq

import harness

TOKEN = "5" * 32
SCENE = os.path.join(harness.ROOT, "scenarios", "beam_only.toml")


def section(path, name):
    with open(path, "rb") as f:
        return tomllib.load(f)[name]


class Program:
    """A structure participant to start by hand, its [structure] config and an ADVANCE that runs for minutes."""

    def __init__(self, name, argv, config, long_substeps):
        self.name, self.argv, self.config, self.long_substeps = name, argv, config, long_substeps


def programs():
    return [
        Program("sphfsi-structure", [os.path.join(harness.BIN, "sphfsi-structure")], section(SCENE, "structure"),
                2 ** 31),  # ~10 us a sub-step: hours
        Program("rigid_plate.py", ["/usr/bin/python3", os.path.join(harness.PARTICIPANTS, "rigid_plate.py")],
                section(os.path.join(harness.SCENES, "rigid_plate_step.toml"), "structure"),
                10_000_000),  # its own limit; a few us a sub-step in Python: tens of seconds
    ]


def f8(rows, cols=2, values=None):
    values = values if values is not None else [0.0] * (rows * cols)
    return {"dtype": "f8", "shape": [rows, cols], "data": struct.pack("<%dd" % len(values), *values)}


class Coordinator:
    """A ROUTER socket on 127.0.0.1 and the one participant that connected to it."""

    def __init__(self):
        self.ctx = zmq.Context()
        self.sock = self.ctx.socket(zmq.ROUTER)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.bind("tcp://127.0.0.1:*")
        self.endpoint = self.sock.getsockopt_string(zmq.LAST_ENDPOINT)
        self.peer = None
        self.progress = 0  # from the participant's last HEARTBEAT

    def receive(self, timeout_s=10.0, beat_every=None):
        """The next message that is not a HEARTBEAT, or None after timeout_s. With beat_every, sends a
        HEARTBEAT that often while it waits, as the real coordinator does."""
        end = time.monotonic() + timeout_s
        next_beat = time.monotonic()
        while True:
            now = time.monotonic()
            if now >= end:
                return None
            if beat_every is not None and now >= next_beat:
                self.heartbeat()
                next_beat = now + beat_every
            until = min(end, next_beat) if beat_every is not None else end
            if not self.sock.poll(max(1, int((until - now) * 1000))):
                continue
            peer, payload = self.sock.recv_multipart()
            self.peer = peer
            m = msgpack.unpackb(payload, raw=False)  # raises on a str that is not UTF-8
            if m["type"] == "HEARTBEAT":
                self.progress = m["body"]["progress"]
                continue
            return m

    def send_raw(self, envelope):
        self.send_bytes(msgpack.packb(envelope, use_bin_type=True))

    def send_bytes(self, payload):
        self.sock.send_multipart([self.peer, payload])

    def send(self, type_, seq, body):
        self.send_raw({"v": 1, "type": type_, "seq": seq, "token": TOKEN, "body": body})

    def request(self, type_, seq, body, timeout_s=10.0):
        self.send(type_, seq, body)
        return self.receive(timeout_s)

    def heartbeat(self):
        if self.peer is not None:
            self.send("HEARTBEAT", 0, {"progress": 0})

    def close(self):
        if not self.sock.closed:
            self.sock.close()
            self.ctx.term()


class Session:
    """One participant process started by hand against a Coordinator, welcomed."""

    def __init__(self, argv, heartbeat_s=0.5, timeout_s=10.0):
        self.c = Coordinator()
        self.log = tempfile.TemporaryFile(mode="w+")
        self.proc = subprocess.Popen([*argv, "--connect", self.c.endpoint, "--name", "structure"],
                                     env=dict(os.environ, SPHFSI_TOKEN=TOKEN), stdout=self.log,
                                     stderr=subprocess.STDOUT, text=True)
        hello = self.c.receive()
        assert hello is not None and hello["type"] == "HELLO", hello
        self.c.send_raw({"v": 1, "type": "WELCOME", "seq": hello["seq"], "token": TOKEN,
                         "body": {"version": 1, "heartbeat_s": heartbeat_s, "timeout_s": timeout_s}})

    def init(self, config, seq=2, t0=0.0, interface=None):
        ready = self.c.request("INIT", seq, {"config": config, "t0": t0, "interface": interface, "state": b""},
                               timeout_s=30)
        assert ready is not None and ready["type"] == "READY" and ready["seq"] == seq, brief(ready)
        return ready

    def output(self):
        self.log.seek(0)
        return self.log.read()

    def wait(self, timeout_s):
        """The exit status, or None if the process still runs after timeout_s."""
        try:
            return self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            return None

    def close(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(timeout=10)
        self.c.close()
        self.log.close()


def vertices(ready):
    mesh = ready["body"]["interface"]
    return mesh["vertices"]["shape"][0] if mesh is not None else 0


def advance(t, dt, n, substeps=1, **inputs):
    return {"t": t, "dt": dt, "substeps": substeps, "iteration": 0, "inputs": inputs or {"force": f8(n)}}


def brief(m):
    """A message for an assertion's text: bulk data left out."""
    if isinstance(m, dict):
        return {k: brief(v) for k, v in m.items() if k not in ("interface", "outputs", "fields")}
    if isinstance(m, list):
        return [brief(x) for x in m]
    return m if not isinstance(m, bytes) else f"<{len(m)} bytes>"


def expect_error(reply, seq, code, mentions=None):
    assert reply is not None, f"no answer to seq {seq}"
    assert reply["type"] == "ERROR", brief(reply)
    assert reply["body"]["code"] == code, brief(reply)
    assert reply["seq"] == seq and reply["body"]["in_reply_to"] == seq, brief(reply)
    if mentions is not None:
        assert mentions in reply["body"]["message"], brief(reply)


def with_bad_utf8(envelope, placeholder):
    """The envelope packed, with the str `placeholder` (4 ASCII characters) turned into 4 bytes that are not
    UTF-8: msgpack-python itself only writes valid UTF-8."""
    packed = msgpack.packb(envelope, use_bin_type=True)
    old = b"\xa4" + placeholder.encode()
    assert len(placeholder) == 4 and packed.count(old) == 1
    return packed.replace(old, b"\xa4\xff\xfe\x1bX")


def test_runtime_answers_as_the_protocol_document_says():
    s = Session([os.path.join(harness.BIN, "sphfsi-structure")])
    c = s.c
    try:
        # A message whose seq is readable but whose body has a key not in the version: refused by its seq.
        expect_error(c.request("ADVANCE", 5, dict(advance(0.0, 1e-3, 0), colour="blue")), 5, "bad_message")
        # Unreadable bytes: refused with seq and in_reply_to 0.
        c.send_bytes(b"\xc1 not msgpack")
        expect_error(c.receive(), 0, "bad_message")
        # Before INIT, any request but INIT and BYE is bad_state.
        expect_error(c.request("SAVE", 6, {}), 6, "bad_state")
        # An ERROR from the coordinator is not a request: logged, never answered.
        c.send_raw({"v": 1, "type": "ERROR", "seq": 7, "token": TOKEN,
                    "body": {"code": "internal", "message": "a test ERROR", "in_reply_to": 0}})
        c.send_raw({"v": 1, "type": "ERROR", "seq": 7, "token": "wrong",  # whatever its token
                    "body": {"code": "internal", "message": "a stray ERROR", "in_reply_to": 0}})
        # Nor is a malformed HEARTBEAT or ERROR answered (an answer to one would arrive before READY below).
        c.send_raw({"v": 1, "type": "HEARTBEAT", "seq": 7, "token": TOKEN, "body": {"progress": "lots"}})
        c.send_raw({"v": 1, "type": "ERROR", "seq": 7, "token": TOKEN, "body": {"code": "internal"}})
        ready = s.init(section(SCENE, "structure"), seq=8)  # not an answer to 7
        n = vertices(ready)
        # RESTORE before any SAVE, and ADVANCE from a time that is not the participant's: bad_state.
        expect_error(c.request("RESTORE", 9, {}), 9, "bad_state")
        expect_error(c.request("ADVANCE", 10, advance(0.5, 1e-3, n)), 10, "bad_state")
        # A window length that is not > 0, or a start that is not finite, is out of range: bad_message.
        expect_error(c.request("ADVANCE", 10, advance(0.0, 0.0, n)), 10, "bad_message")
        expect_error(c.request("ADVANCE", 10, advance(float("nan"), 1e-3, n)), 10, "bad_message")
        # From WELCOME on every message is in the agreed version (1 here): one in another is version_mismatch.
        c.send_raw({"v": 2, "type": "SAVE", "seq": 10, "token": TOKEN, "body": {}})
        expect_error(c.receive(), 10, "version_mismatch")
        # And the participant is still well: it advances, then leaves on BYE with status 0.
        advanced = c.request("ADVANCE", 11, advance(0.0, 1e-3, n))
        assert advanced["type"] == "ADVANCED" and abs(advanced["body"]["t"] - 1e-3) < 1e-15, advanced
        bye = c.request("BYE", 12, {})
        assert bye["type"] == "ACK" and bye["seq"] == 12, bye
        assert s.wait(10) == 0, s.output()
        assert "the coordinator sent ERROR internal: a test ERROR" in s.output(), s.output()
    finally:
        s.close()


def test_a_welcome_outside_what_was_offered_is_refused():
    """A WELCOME choosing a version the participant did not offer, or a timeout that is not a finite number
    > 0 (a NaN one never expired: the participant would outlive a silent coordinator), is not taken: the
    participant exits 3, as without a WELCOME. Found by a review, 2026-11-27."""
    for body, why in [({"version": 99, "heartbeat_s": 0.5, "timeout_s": 3.0}, "chose protocol 99"),
                      ({"version": 1, "heartbeat_s": 0.5, "timeout_s": float("nan")}, "malformed answer to HELLO")]:
        c = Coordinator()
        with tempfile.TemporaryFile(mode="w+") as log:
            proc = subprocess.Popen([os.path.join(harness.BIN, "sphfsi-structure"), "--connect", c.endpoint, "--name",
                                     "structure", "--startup-timeout", "1"], env=dict(os.environ, SPHFSI_TOKEN=TOKEN),
                                    stdout=log, stderr=subprocess.STDOUT, text=True)
            hello = c.receive()
            assert hello is not None and hello["type"] == "HELLO", hello
            c.send_raw({"v": 1, "type": "WELCOME", "seq": hello["seq"], "token": TOKEN, "body": body})
            code = proc.wait(timeout=10)
            log.seek(0)
            text = log.read()
        c.close()
        assert code == 3 and why in text, (code, text)


def test_sigterm_before_welcome_exits_130_saying_so():
    """Stopped while it waits for WELCOME, the runtime exited 3 ("no WELCOME ... within 10 s", after 1 s),
    which the coordinator names "refused, or no WELCOME" (a review, 2026-11-28). A stop is 130."""
    c = Coordinator()
    with tempfile.TemporaryFile(mode="w+") as log:
        proc = subprocess.Popen([os.path.join(harness.BIN, "sphfsi-structure"), "--connect", c.endpoint, "--name",
                                 "structure"], env=dict(os.environ, SPHFSI_TOKEN=TOKEN), stdout=log,
                                stderr=subprocess.STDOUT, text=True)
        hello = c.receive()
        assert hello is not None and hello["type"] == "HELLO", hello
        proc.send_signal(signal.SIGTERM)  # no WELCOME comes
        code = proc.wait(timeout=10)
        log.seek(0)
        text = log.read()
    c.close()
    assert code == 130 and "stopped by signal before WELCOME" in text, (code, text)


def test_init_with_a_start_time_that_is_not_finite_is_bad_message_and_may_be_retried():
    # A NaN or infinite t0 used to be taken as the solver's clock: every ADVANCE then failed with bad_state.
    for p in programs():
        s = Session(p.argv)
        try:
            for seq, t0 in ((2, float("nan")), (3, float("inf")), (4, -float("inf"))):
                reply = s.c.request("INIT", seq, {"config": p.config, "t0": t0, "interface": None, "state": b""})
                expect_error(reply, seq, "bad_message", mentions="t0")
            # A failed INIT leaves the participant WELCOMED: INIT may be tried again.
            n = vertices(s.init(p.config, seq=5))
            advanced = s.c.request("ADVANCE", 6, advance(0.0, 1e-3, n))
            assert advanced["type"] == "ADVANCED", (p.name, brief(advanced))
        finally:
            s.close()


def test_init_from_a_state_that_cannot_be_used_is_bad_config():
    """docs/protocol.md, INIT: a state the participant cannot read, or one at another time than t0, is
    bad_config. rigid_plate.py answered bad_message (a review, 2026-11-28)."""
    for p in programs():
        s = Session(p.argv)
        try:
            reply = s.c.request("INIT", 2, {"config": p.config, "t0": 0.0, "interface": None, "state": b"not a state"})
            expect_error(reply, 2, "bad_config")
            s.init(p.config, seq=3)
            state = s.c.request("CHECKPOINT", 4, {})
            assert state is not None and state["type"] == "STATE", (p.name, brief(state))
        finally:
            s.close()
        s = Session(p.argv)
        try:  # the checkpoint, taken at t = 0, offered at t0 = 1 s
            reply = s.c.request("INIT", 2, {"config": p.config, "t0": 1.0, "interface": None,
                                            "state": state["body"]["state"]})
            expect_error(reply, 2, "bad_config")
        finally:
            s.close()


def test_init_after_ready_is_bad_state_and_leaves_the_state_alone():
    # A second INIT used to re-initialise the solver silently, back to its t0.
    for p in programs():
        s = Session(p.argv)
        try:
            n = vertices(s.init(p.config, seq=2))
            assert s.c.request("ADVANCE", 3, advance(0.0, 1e-3, n))["type"] == "ADVANCED"
            reply = s.c.request("INIT", 4, {"config": p.config, "t0": 0.0, "interface": None, "state": b""})
            expect_error(reply, 4, "bad_state", mentions="INIT")
            advanced = s.c.request("ADVANCE", 5, advance(1e-3, 1e-3, n))  # still at t = 1 ms
            assert advanced["type"] == "ADVANCED" and abs(advanced["body"]["t"] - 2e-3) < 1e-15, (p.name, brief(advanced))
        finally:
            s.close()


def test_after_an_advance_that_failed_part_way_only_restore_is_answered():
    """A structure driven to blow up inside a window (a force of 1e300 N: 'diverged' at a sub-step) holds a
    state part-way through it. A FRAME then paired the window start's t with it (a review, 2026-11-27: t = 0
    with a node 822 m away). SNAPSHOT, CHECKPOINT, SAVE and ADVANCE are now bad_state until RESTORE brings
    back the saved state, which answers again, at its own time."""
    s = Session([os.path.join(harness.BIN, "sphfsi-structure")])
    c = s.c
    try:
        n = vertices(s.init(section(SCENE, "structure"), seq=2))
        assert c.request("SAVE", 3, {})["type"] == "ACK"
        huge = f8(n, values=[1e300] * (2 * n))
        failed = c.request("ADVANCE", 4, advance(0.0, 1e-3, n, substeps=10, force=huge))
        assert failed["type"] == "ERROR" and failed["body"]["code"] == "diverged", brief(failed)
        for seq, (type_, body) in enumerate((("SNAPSHOT", {}), ("CHECKPOINT", {}), ("SAVE", {}),
                                             ("ADVANCE", advance(0.0, 1e-3, n))), start=5):
            expect_error(c.request(type_, seq, body), seq, "bad_state", mentions="after a failed ADVANCE")
        assert c.request("RESTORE", 9, {})["type"] == "ACK"
        frame = c.request("SNAPSHOT", 10, {})
        assert frame["type"] == "FRAME" and frame["body"]["t"] == 0.0, brief(frame)
        advanced = c.request("ADVANCE", 11, advance(0.0, 1e-3, n))
        assert advanced["type"] == "ADVANCED", brief(advanced)
    finally:
        s.close()


def test_structure_advance_takes_exactly_force():
    # A missing `force` used to be taken as zero, an extra field ignored.
    for p in programs():
        s = Session(p.argv)
        try:
            n = vertices(s.init(p.config, seq=2))
            expect_error(s.c.request("ADVANCE", 3, dict(advance(0.0, 1e-3, n), inputs={})), 3, "bad_message",
                         mentions="force")
            extra = advance(0.0, 1e-3, n, force=f8(n), colour=f8(n))
            expect_error(s.c.request("ADVANCE", 4, extra), 4, "bad_message", mentions="colour")
            wrong = advance(0.0, 1e-3, n, velocity=f8(n))
            expect_error(s.c.request("ADVANCE", 5, wrong), 5, "bad_message", mentions="force")
            # Shapes are still checked, and the right inputs still work.
            expect_error(s.c.request("ADVANCE", 6, advance(0.0, 1e-3, n, force=f8(n + 1))), 6, "bad_message")
            assert s.c.request("ADVANCE", 7, advance(0.0, 1e-3, n))["type"] == "ADVANCED"
        finally:
            s.close()


def test_fluid_advance_takes_exactly_the_inputs_of_its_run():
    config = section(os.path.join(harness.ROOT, "scenarios", "fluid_only.toml"), "fluid")
    config["dp"] = 0.02
    # A plate lying in the water: vertices 0..3, one cell.
    plate = [0.2, 0.3, 0.3, 0.3, 0.3, 0.34, 0.2, 0.34]
    mesh = {"vertices": f8(4, 2, plate), "cells": {"dtype": "i4", "shape": [1, 4],
                                                    "data": struct.pack("<4i", 0, 1, 2, 3)}}
    fluid = [os.path.join(harness.BIN, "sphfsi-fluid")]
    s = Session(fluid)  # alone: no inputs at all
    try:
        s.init(config)
        expect_error(s.c.request("ADVANCE", 3, advance(0.0, 1e-3, 0, displacement=f8(4))), 3, "bad_message",
                     mentions="displacement")
        assert s.c.request("ADVANCE", 4, dict(advance(0.0, 1e-3, 0), inputs={}))["type"] == "ADVANCED"
    finally:
        s.close()
    s = Session(fluid)  # coupled: displacement and velocity, both
    try:
        s.init(config, interface=mesh)
        expect_error(s.c.request("ADVANCE", 3, dict(advance(0.0, 1e-3, 0), inputs={})), 3, "bad_message",
                     mentions="displacement")
        expect_error(s.c.request("ADVANCE", 4, advance(0.0, 1e-3, 0, displacement=f8(4))), 4, "bad_message",
                     mentions="velocity")
        both = {"displacement": f8(4), "velocity": f8(4)}
        expect_error(s.c.request("ADVANCE", 5, advance(0.0, 1e-3, 0, force=f8(4), **both)), 5, "bad_message",
                     mentions="force")
        advanced = s.c.request("ADVANCE", 6, advance(0.0, 1e-3, 0, **both))
        assert advanced["type"] == "ADVANCED" and advanced["body"]["outputs"]["force"]["shape"] == [4, 2], advanced
    finally:
        s.close()


def test_replies_quoting_bytes_that_are_not_utf8_are_utf8():
    # The type name (and a config key) used to be echoed byte for byte into the ERROR message, a msgpack str
    # that a strict reader (msgpack-python with raw=False) cannot decode.
    for p in programs():
        s = Session(p.argv)
        try:
            s.c.send_bytes(with_bad_utf8({"v": 1, "type": "QQQQ", "seq": 3, "token": TOKEN, "body": {}}, "QQQQ"))
            reply = s.c.receive()  # would raise UnicodeDecodeError
            assert reply is not None and reply["type"] == "ERROR", (p.name, brief(reply))
            if p.name == "sphfsi-structure":  # rigid_plate.py cannot read such a message at all: bad_message, seq 0
                expect_error(reply, 3, "unknown_type", mentions="\\xff\\xfe\\x1bX")
            config = dict(p.config, KKKK=1.0)
            s.c.send_bytes(with_bad_utf8({"v": 1, "type": "INIT", "seq": 4, "token": TOKEN, "body": {
                "config": config, "t0": 0.0, "interface": None, "state": b""}}, "KKKK"))
            reply = s.c.receive()
            assert reply is not None and reply["type"] == "ERROR", (p.name, brief(reply))
            if p.name == "sphfsi-structure":  # the bad key is quoted, escaped (a reply without it proves nothing)
                expect_error(reply, 4, "bad_config", mentions="\\xff\\xfe\\x1bX")
            # The participant is still well.
            assert vertices(s.init(p.config, seq=5)) >= 0
        finally:
            s.close()


# ---- a participant busy in a long ADVANCE --------------------------------------------------------------------

def start_long_advance(p, heartbeat_s=0.2, timeout_s=1.0):
    """A participant welcomed with these periods, initialised and busy in an ADVANCE of minutes; the
    coordinator keeps beating until the participant's heartbeats show progress."""
    s = Session(p.argv, heartbeat_s=heartbeat_s, timeout_s=timeout_s)
    n = vertices(s.init(p.config))
    s.c.send("ADVANCE", 3, advance(0.0, 1.0, n, substeps=p.long_substeps))
    end = time.monotonic() + 20
    while s.c.progress == 0 and time.monotonic() < end:
        assert s.c.receive(0.1, beat_every=heartbeat_s) is None
    assert s.c.progress > 0 and s.proc.poll() is None, (p.name, s.output())
    return s, n


def test_sigterm_ends_a_long_advance_at_once():
    # The runtime's handler only set a flag, read between messages: a participant busy in a long ADVANCE
    # outlived its coordinator (the launcher's parent-death signal is SIGTERM) at 100 % CPU.
    for p in programs():
        s, _ = start_long_advance(p)
        try:
            s.c.receive(0.5, beat_every=0.2)  # the coordinator is alive: it is the signal that ends it
            s.proc.send_signal(signal.SIGTERM)
            start = time.monotonic()
            code = s.wait(5)
            assert code == 130, (p.name, code, s.output())
            assert time.monotonic() - start < 2.0, (p.name, time.monotonic() - start)
            assert "signal" in s.output(), s.output()
        finally:
            s.close()


def test_a_vanished_coordinator_ends_a_long_advance_within_timeout():
    # Started by hand (no parent-death signal), a participant whose coordinator went away in the middle of
    # a long ADVANCE only noticed after the ADVANCE, minutes later.
    for p in programs():
        s, _ = start_long_advance(p, timeout_s=1.0)
        try:
            s.c.close()  # the coordinator's socket goes away: nothing more arrives
            start = time.monotonic()
            code = s.wait(1.0 + 4.0)
            assert code == 4, (p.name, code, s.output())
            assert "silent" in s.output() or "heard nothing" in s.output(), s.output()
            assert time.monotonic() - start > 0.5, "exited before timeout_s"
        finally:
            s.close()


def test_a_long_advance_outlives_timeout_while_the_coordinator_beats_and_keeps_messages_in_order():
    # What the heartbeat thread takes while the main thread computes: HEARTBEATs count as signs of life,
    # anything else waits for the main thread, in order.
    for p in programs():
        s = Session(p.argv, heartbeat_s=0.2, timeout_s=1.0)
        try:
            n = vertices(s.init(p.config))
            probe = 100_000 if p.name == "rigid_plate.py" else 10_000  # ~0.1 s
            r = s.c.request("ADVANCE", 3, advance(0.0, 1e-3, n, substeps=probe), timeout_s=30)
            assert r["type"] == "ADVANCED", r
            per_step = max(r["body"]["compute_s"], 1e-6) / probe
            # About 4 s, four times timeout_s: room for the probe to have run slower than this ADVANCE will.
            substeps = max(probe, min(p.long_substeps, int(4.0 / per_step)))
            before = s.c.progress
            s.c.send("ADVANCE", 20, advance(1e-3, 1e-3, n, substeps=substeps))
            end = time.monotonic() + 10
            while s.c.progress <= before and time.monotonic() < end:
                assert s.c.receive(0.05, beat_every=0.2) is None
            s.c.send_raw({"v": 1, "type": "HEARTBEAT", "seq": 0, "token": "wrong", "body": {"progress": 0}})
            s.c.send("SAVE", 21, {})
            s.c.send("SNAPSHOT", 22, {})
            replies = [s.c.receive(60, beat_every=0.2) for _ in range(3)]
            assert [(m["type"], m["seq"]) for m in replies] == [("ADVANCED", 20), ("ACK", 21), ("FRAME", 22)], brief(replies)
            assert replies[0]["body"]["compute_s"] > 1.0, (p.name, replies[0]["body"]["compute_s"])  # > timeout_s
            assert s.proc.poll() is None, s.output()
            assert s.c.request("BYE", 23, {})["type"] == "ACK"
            assert s.wait(10) == 0, s.output()
        finally:
            s.close()


def test_a_reply_that_cannot_leave_does_not_outlive_a_vanished_coordinator():
    """The coordinator vanishes in the middle of an ADVANCE of about 2 s while HEARTBEATs every 1 ms fill
    ZeroMQ's queue of 1000 messages. The reply then blocked in send holding the socket's mutex, and the
    heartbeat thread, which ends a participant whose coordinator fell silent, waited on that mutex: the
    process stayed for ever (a review, 2026-11-28). It must end with status 4 within timeout_s (4 s)."""
    p = programs()[0]  # sphfsi-structure: the runtime under test is ours (rigid_plate.py has its own)
    s = Session(p.argv, heartbeat_s=0.001, timeout_s=4.0)
    try:
        n = vertices(s.init(p.config))
        probe = 10_000
        r = s.c.request("ADVANCE", 3, advance(0.0, 1e-3, n, substeps=probe), timeout_s=30)
        assert r["type"] == "ADVANCED", r
        per_step = max(r["body"]["compute_s"], 1e-6) / probe
        s.c.send("ADVANCE", 4, advance(1e-3, 1e-3, n, substeps=max(probe, int(2.0 / per_step))))
        s.c.close()
        start = time.monotonic()
        code = s.wait(4.0 + 6.0)
        assert code == 4, (code, time.monotonic() - start, s.output())
        assert "silent" in s.output(), s.output()
    finally:
        s.close()


def cpu_seconds(pid):
    """User + system CPU time of a process (0 once it is gone)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (FileNotFoundError, ProcessLookupError, IndexError):
        return 0.0


def test_participant_follows_a_killed_coordinator_out_of_a_long_advance():
    # The adversarial report: the structure, busy in an ADVANCE of 10^7 sub-steps, kept running at 99 % CPU
    # for > 45 s after its coordinator was SIGKILLed.
    out = harness.out_dir("follow")
    run = harness.Running("run", SCENE, "--out", out, "--quiet", "--set", "structure.time.dt_max=1e-7",
                          "--set", "run.output_interval=1.0")
    pid = harness.participant_pid(run.wait_for("structure connected"))
    try:
        # Into the ADVANCE: INIT and the first frame take milliseconds, so 0.5 s of CPU is the long window.
        deadline = time.time() + 20
        while cpu_seconds(pid) < 0.5 and time.time() < deadline:
            time.sleep(0.05)
        assert cpu_seconds(pid) >= 0.5, "the structure never got busy"
        run.proc.kill()
        run.proc.wait(timeout=10)
        deadline = time.time() + 5
        while harness.pid_alive(pid) and time.time() < deadline:
            time.sleep(0.05)
        assert not harness.pid_alive(pid), "sphfsi-structure outlived a SIGKILLed coordinator"
    finally:
        if harness.pid_alive(pid):
            os.kill(pid, signal.SIGKILL)


if __name__ == "__main__":
    harness.main(globals())
