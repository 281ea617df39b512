"""The reference participant runtime (protocol/src/participant.cpp) keeps the rules of docs/protocol.md,
§3 "Rules": this test plays the coordinator by hand against a real sphfsi-structure over 127.0.0.1 and
checks the answers a replacement solver's author would rely on. Every wait is bounded."""
import os
import subprocess
import tomllib

import msgpack
import zmq

import harness

TOKEN = "5" * 32
SCENE = os.path.join(harness.ROOT, "scenarios", "beam_only.toml")


class Coordinator:
    """A ROUTER socket on 127.0.0.1 and the one participant that connected to it."""

    def __init__(self):
        self.ctx = zmq.Context()
        self.sock = self.ctx.socket(zmq.ROUTER)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.bind("tcp://127.0.0.1:*")
        self.endpoint = self.sock.getsockopt_string(zmq.LAST_ENDPOINT)
        self.peer = None

    def receive(self, timeout_s=10.0):
        """The next message that is not a HEARTBEAT, or None after timeout_s."""
        while self.sock.poll(int(timeout_s * 1000)):
            peer, payload = self.sock.recv_multipart()
            self.peer = peer
            m = msgpack.unpackb(payload, raw=False)
            if m["type"] != "HEARTBEAT":
                return m
        return None

    def send_raw(self, envelope):
        self.sock.send_multipart([self.peer, msgpack.packb(envelope, use_bin_type=True)])

    def request(self, type_, seq, body):
        self.send_raw({"v": 1, "type": type_, "seq": seq, "token": TOKEN, "body": body})
        return self.receive()

    def close(self):
        self.sock.close()
        self.ctx.term()


def expect_error(reply, seq, code):
    assert reply is not None, f"no answer to seq {seq}"
    assert reply["type"] == "ERROR", reply
    assert reply["body"]["code"] == code, reply
    assert reply["seq"] == seq and reply["body"]["in_reply_to"] == seq, reply


def test_runtime_answers_as_the_protocol_document_says():
    with open(SCENE, "rb") as f:
        config = tomllib.load(f)["structure"]
    c = Coordinator()
    env = dict(os.environ, SPHFSI_TOKEN=TOKEN)
    proc = subprocess.Popen([os.path.join(harness.BIN, "sphfsi-structure"), "--connect", c.endpoint,
                             "--name", "structure"], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)
    try:
        hello = c.receive()
        assert hello is not None and hello["type"] == "HELLO", hello
        c.send_raw({"v": 1, "type": "WELCOME", "seq": hello["seq"], "token": TOKEN,
                    "body": {"version": 1, "heartbeat_s": 0.5, "timeout_s": 10.0}})

        # A message whose seq is readable but whose body has a key not in the version: refused by its seq.
        advance = {"t": 0.0, "dt": 1e-3, "substeps": 1, "iteration": 0, "inputs": {}}
        expect_error(c.request("ADVANCE", 5, dict(advance, colour="blue")), 5, "bad_message")
        # Unreadable bytes: refused with seq and in_reply_to 0.
        c.sock.send_multipart([c.peer, b"\xc1 not msgpack"])
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
        ready = c.request("INIT", 8, {"config": config, "t0": 0.0, "interface": None, "state": b""})
        assert ready is not None and ready["type"] == "READY" and ready["seq"] == 8, ready  # not an answer to 7
        # RESTORE before any SAVE, and ADVANCE from a time that is not the participant's: bad_state.
        expect_error(c.request("RESTORE", 9, {}), 9, "bad_state")
        expect_error(c.request("ADVANCE", 10, dict(advance, t=0.5)), 10, "bad_state")
        # A window length that is not > 0, or a start that is not finite, is out of range: bad_message.
        expect_error(c.request("ADVANCE", 10, dict(advance, dt=0.0)), 10, "bad_message")
        expect_error(c.request("ADVANCE", 10, dict(advance, t=float("nan"))), 10, "bad_message")
        # And the participant is still well: it advances, then leaves on BYE with status 0.
        advanced = c.request("ADVANCE", 11, advance)
        assert advanced["type"] == "ADVANCED" and abs(advanced["body"]["t"] - 1e-3) < 1e-15, advanced
        bye = c.request("BYE", 12, {})
        assert bye["type"] == "ACK" and bye["seq"] == 12, bye
        out, _ = proc.communicate(timeout=10)
        assert proc.returncode == 0, out
        assert "the coordinator sent ERROR internal: a test ERROR" in out, out
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=10)
        c.close()


if __name__ == "__main__":
    harness.main(globals())
