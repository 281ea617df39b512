#!/usr/bin/env -S /usr/bin/python3
"""A structure participant that misbehaves on purpose, for the coordinator's failure tests.

It is a foreign program speaking docs/protocol.md (not a stand-in for one of ours): the coordinator
must name it and shut the run down within its timeout whatever it does. The scene's [structure]
section picks the fault:
  mode = "garbage"        answers the first ADVANCE with bytes that are not MessagePack
  mode = "crash"          exits with status 7 on the first ADVANCE
  mode = "silent"         stops answering and stops heartbeats after INIT (a hang)
  mode = "version"        says HELLO with protocol version 99 only
  mode = "error"          answers the first ADVANCE with ERROR diverged
  mode = "error_exit"     answers the first ADVANCE with ERROR diverged and exits with status 1 at once
  mode = "wrong_seq"      answers the first ADVANCE with a seq that is not the request's
  mode = "early"          sends an ADVANCED right after READY, before any ADVANCE was asked for
  mode = "wrong_reply"    answers the first ADVANCE with ACK
  mode = "wrong_time"     reports reaching t + dt + 1 s
  mode = "empty_state"    answers CHECKPOINT with a STATE without bytes
  mode = "wrong_kind"     says HELLO with kind "fluid" (from the env, like "version")
  mode = "fluid_v1"       says HELLO as a fluid speaking protocol 1 only (from the env; for the fluid role)
  mode = "frame_time"     sends a FRAME field named "time" (the recorder's own)
  mode = "frame_bad_name" sends a FRAME field named ""
  mode = "frame_changes"  sends field y in its first FRAME, y and zz in the next
  mode = "frame_empty"    sends a FRAME field of shape [0, 4294967296]
  mode = "info_bad_key"   sends READY info with a key ""
  mode = "info_huge"      sends READY info with 200,000 keys
  mode = "info_twice"     sends READY info {"a.b": 1, "a": {"b": "x"}} (one attribute name twice)
  mode = "info_software"  sends READY info {"software": "forged"} (the HELLO's own attribute)
  mode = "info_array"     sends READY info {"arr": [1, 2, 3]}
  mode = "info_not_utf8"  sends READY info {"s": <the 4 bytes ff fe 1b 58, not UTF-8>}
  mode = "info_nul"       sends READY info {"s": "a\\0b"} (a NUL inside)
  mode = "software_nul"   says HELLO software "mis\\0behaving" (from the env, like "version")
  mode = "no_mesh"        answers READY with interface nil (no wetted surface)
  mode = "exit_after_reply"  answers the first ADVANCE, then closes its socket and exits with status 9 at once
  mode = "ready_dt_zero"  sends READY with dt_wanted 0
  mode = "stats_text"     reports ADVANCED stats with a string value
  mode = "stats_bad_name" reports ADVANCED stats named "a/b" (it would become an HDF5 group)
  mode = "stats_nan"      reports ADVANCED stats kinetic_energy = NaN
  mode = "stats_many"     reports 300 ADVANCED stats
  mode = "stats_late"     reports the ADVANCED stat "late" from its second window on (not a fault)
  mode = "bad_exit"       answers BYE with ACK, then exits with status 5
  mode = "hang_snapshot"  never answers SNAPSHOT while its heartbeats go on
  mode = "snapshot_error" answers SNAPSHOT with ERROR diverged from t = fail_at on (a key of [structure])
  mode = "wrong_token"    answers the first ADVANCE with a wrong token, then prints the reply's type and version
  mode = "heartbeat_own_socket"  sends its heartbeats on a second socket and takes 3 s over the first ADVANCE
  mode = "stall"          never answers the first ADVANCE while its heartbeats go on, progress standing still
  mode = "overflow"       as a structure, moves vertex 0 by +1e308 m in x at iteration 0 and -1e308 m at later ones:
                          finite answers whose implicit iterate overflows
  mode = "tiny_step"      wants a step of 1e-19 s in every ADVANCED (a step that collapsed: windows that short
                          would never reach the end)
Otherwise it answers like a structure that does not move. Started with --name fluid it is a fluid instead (it
says so at HELLO and answers with a zero force), so that a coupled scene can run two of it; it acknowledges
SAVE and RESTORE, which implicit coupling asks for.
"""
import os
import struct
import sys
import threading
import time

import msgpack
import zmq


def main():
    args = dict(zip(sys.argv[1::2], sys.argv[2::2]))
    token = os.environ.get("SPHFSI_TOKEN", args.get("--token", ""))
    sock = zmq.Context().socket(zmq.DEALER)
    sock.setsockopt(zmq.LINGER, 0)
    sock.connect(args["--connect"])
    lock = threading.Lock()
    beating = threading.Event()

    def send(kind, seq, body, v=1, wrong_token=False):
        packed = msgpack.packb({"v": v, "type": kind, "seq": seq, "token": "not-it" if wrong_token else token,
                                "body": body}, use_bin_type=True)
        # msgpack-python writes only valid UTF-8: the str "QQQQ" is turned into 4 bytes that are not.
        packed = packed.replace(b"\xa4QQQQ", b"\xa4\xff\xfe\x1bX")
        with lock:
            sock.send(packed)

    def recv(timeout_s=10.0):
        end = time.time() + timeout_s
        while time.time() < end:
            with lock:
                if sock.poll(50):
                    return msgpack.unpackb(sock.recv(), raw=False)
        sys.exit("misbehaving: coordinator silent")

    # The mode arrives only with INIT; a version fault must show at HELLO, so it may also come from the env.
    mode = os.environ.get("MISBEHAVE", "")
    version = 99 if mode == "version" else 1
    kind_said = "fluid" if mode in ("wrong_kind", "fluid_v1") or args.get("--name") == "fluid" else "structure"
    send("HELLO", 1, {"name": args.get("--name", "structure"), "kind": kind_said, "version_min": version,
                      "version_max": version, "software": "mis\0behaving.py" if mode == "software_nul" else "misbehaving.py",
                      "pid": os.getpid()}, v=version)
    reply = recv()
    if reply["type"] != "WELCOME":
        print("misbehaving: refused:", reply["body"].get("message"), file=sys.stderr)
        sys.exit(3)

    stalled = threading.Event()

    def heartbeat():
        n = 0
        own = None
        while beating.is_set():
            n += 1
            if mode == "heartbeat_own_socket" and own is None:  # the mode comes with INIT
                own = sock.context.socket(zmq.DEALER)  # the coordinator never heard HELLO on this one
                own.setsockopt(zmq.LINGER, 0)
                own.connect(args["--connect"])
            if own is not None:
                own.send(msgpack.packb({"v": 1, "type": "HEARTBEAT", "seq": 1000 + n, "token": token,
                                        "body": {"progress": n}}, use_bin_type=True))
            else:
                send("HEARTBEAT", 1000 + n, {"progress": 0 if stalled.is_set() else n})
            time.sleep(0.2)

    beating.set()
    threading.Thread(target=heartbeat, daemon=True).start()
    def f8(rows, values):
        return {"dtype": "f8", "shape": [rows, 2], "data": struct.pack("<%dd" % len(values), *values)}

    mesh = {"vertices": f8(4, [0, 0, 1, 0, 1, 0.1, 0, 0.1]),
            "cells": {"dtype": "i4", "shape": [1, 4], "data": struct.pack("<4i", 0, 1, 2, 3)}}
    now = 0.0
    while True:
        msg = recv(30.0)
        kind, seq, body = msg["type"], msg["seq"], msg["body"]
        if kind == "HEARTBEAT":
            continue
        if kind == "INIT":
            mode = body["config"].get("mode", mode)
            fail_at = float(body["config"].get("fail_at", 0.0))
            info = {"info_bad_key": {"": 1}, "info_huge": {f"k{i}": i for i in range(200000)},
                    "info_twice": {"a.b": 1, "a": {"b": "x"}}, "info_software": {"software": "forged"},
                    "info_array": {"arr": [1, 2, 3]}, "info_not_utf8": {"s": "QQQQ"}, "info_nul": {"s": "a\0b"}}.get(mode, {})
            send("READY", seq, {"dt_wanted": 0.0 if mode == "ready_dt_zero" else 0.01,
                                "interface": None if mode == "no_mesh" else mesh, "info": info})
            if mode == "early":
                zero = f8(4, [0.0] * 8)
                send("ADVANCED", seq + 2, {"t": 1.0, "dt_wanted": 0.01, "outputs": {"displacement": zero, "velocity": zero},
                                           "substeps": 1, "solver_iterations": 0, "compute_s": 0.0, "stats": {}})
            if mode == "silent":
                beating.clear()
                time.sleep(3600)
        elif kind == "ADVANCE":
            if mode == "garbage":
                with lock:
                    sock.send(b"\xc1 this is not msgpack")
            elif mode == "crash":
                os._exit(7)
            elif mode in ("error", "error_exit"):
                send("ERROR", seq, {"code": "diverged", "message": "node 3: rotation = nan at t = 0.01 s", "in_reply_to": seq})
                if mode == "error_exit":  # as a script ending in sys.exit(1) would: the ERROR leaves first
                    with lock:
                        sock.close(linger=2000)
                        sock.context.term()  # returns once the ERROR is sent (a closed socket's I/O goes on until then)
                    os._exit(1)
            elif mode == "stall":
                stalled.set()  # the main thread is stuck; the heartbeat thread goes on
                time.sleep(3600)
            elif mode == "wrong_reply":
                send("ACK", seq, {})
            elif mode == "heartbeat_own_socket" and body["t"] == 0:
                time.sleep(3.0)  # past the scene's timeout_s of 2 s, heartbeats going to the other socket
            elif mode == "wrong_token":
                send("ACK", seq, {}, wrong_token=True)
                reply = recv(5.0)
                while reply["type"] == "HEARTBEAT":
                    reply = recv(5.0)
                print(f"misbehaving: answered with {reply['type']} in protocol {reply['v']}", file=sys.stderr, flush=True)
            else:
                now = body["t"] + body["dt"]
                zero = f8(4, [0.0] * 8)
                moved = [0.0] * 8
                if mode == "overflow":
                    moved[0] = 1e308 if body.get("iteration", 0) == 0 else -1e308
                outputs = ({"force": zero} if kind_said == "fluid" and mode not in ("wrong_kind", "fluid_v1")
                           else {"displacement": f8(4, moved), "velocity": zero})
                send("ADVANCED", seq + 7 if mode == "wrong_seq" else seq,
                     {"t": now + 1.0 if mode == "wrong_time" else now, "dt_wanted": 1e-19 if mode == "tiny_step" else 0.01,
                      "outputs": outputs,
                      "substeps": body.get("substeps") or 1, "solver_iterations": 0, "compute_s": 0.0,
                      "stats": {"x": "text"} if mode == "stats_text" else {"a/b": 1.0} if mode == "stats_bad_name"
                      else {"kinetic_energy": float("nan")} if mode == "stats_nan"
                      else {f"s{i}": 1.0 for i in range(300)} if mode == "stats_many"
                      else {"late": 1.0} if mode == "stats_late" and body["t"] > 0 else {}})
                if mode == "exit_after_reply":
                    with lock:
                        sock.close(linger=2000)
                        sock.context.term()  # returns once the reply is sent
                    os._exit(9)
        elif kind == "SNAPSHOT" and mode == "hang_snapshot":
            time.sleep(3600)
        elif kind == "SNAPSHOT" and mode == "snapshot_error" and now >= fail_at - 1e-9:
            send("ERROR", seq, {"code": "diverged", "message": f"frame at t = {now:g} s: node 1 at NaN", "in_reply_to": seq})
        elif kind == "SNAPSHOT":
            one = {"dtype": "f8", "shape": [1, 1], "data": struct.pack("<d", now)}
            fields = {"frame_time": {"time": one}, "frame_bad_name": {"": one},
                      "frame_changes": {"y": one, **({"zz": one} if now > 0 else {})},
                      "frame_empty": {"z": {"dtype": "f8", "shape": [0, 4294967296], "data": b""}}}.get(mode, {})
            send("FRAME", seq, {"t": now, "fields": fields})
        elif kind in ("SAVE", "RESTORE"):
            send("ACK", seq, {})
        elif kind == "CHECKPOINT":
            send("STATE", seq, {"t": now, "state": b"" if mode == "empty_state" else struct.pack("<d", now)})
        elif kind == "BYE":
            send("ACK", seq, {})
            if mode == "bad_exit":
                sock.close()
                os._exit(5)
            return


if __name__ == "__main__":
    main()
