#!/usr/bin/python3
"""An actor that gets one thing of the protocol wrong on purpose, for tests of check-actor and of the director.
With --mode ok it gets everything right (a constant light, or its one input's light passed through), so that each
other mode fails check-actor for its one reason only.

  --mode ok                   a conforming LightOp
  --mode wrong_version        says HELLO with protocol version 2
  --mode silent               never answers a shade request (nor anything else on its data socket)
  --mode crash                exits with status 3 on its first shade request
  --mode no_ready_render      never answers PHASE render with READY render
  --mode no_ready_frame       never answers PHASE frame (a job's next frame) with READY frame
  --mode ignore_input         answers without asking the input it was given
  --mode ignore_sigterm       ignores SIGTERM
  --mode silent_on_malformed  drops malformed packets without an ERROR
  --mode wrong_n              replies with n one more than the points it holds
  --mode no_routing_id        connects to the director without its name as routing id
  --mode crash_at_finish      exits with status 3 on PHASE finish, without STATS or BYE
  --mode no_curve             takes --curve but speaks without CURVE (an actor written without it)
  --mode slow                 conforming, but takes 0.35 s over each shade request (its director must keep
                              it alive meanwhile with HEARTBEATs)
"""
import argparse
import os
import signal
import struct
import sys
import time

import msgpack
import zmq
import zmq.utils.z85

HELLO, CONFIG, PHASE, REQUEST, REPLY, ERROR, STATS, HEARTBEAT, BYE, READY, PEER_DOWN = range(1, 12)
MODES = ["ok", "wrong_version", "silent", "crash", "no_ready_render", "no_ready_frame", "ignore_input", "ignore_sigterm",
         "silent_on_malformed", "wrong_n", "no_routing_id", "crash_at_finish", "no_curve", "slow"]


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--mode", required=True, choices=MODES)
    p.add_argument("--kind", required=True)
    p.add_argument("--name", required=True)
    p.add_argument("--director", required=True)
    p.add_argument("--bind", default="tcp://127.0.0.1:*")
    p.add_argument("--curve", action="store_true")
    a = p.parse_args()
    if a.mode == "ignore_sigterm":
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
    version = 2 if a.mode == "wrong_version" else 1
    ctx = zmq.Context()
    keys = None
    if a.curve and a.mode != "no_curve":  # own public, own secret, director public, the farm's keys
        words = sys.stdin.readline().split()
        keys = (words[1], words[2], words[3], set(words[4:]))
        zap = ctx.socket(zmq.REP)
        zap.bind("inproc://zeromq.zap.01")

    def curve_client(s, server_key):
        if keys:
            s.setsockopt_string(zmq.CURVE_SERVERKEY, server_key)
            s.setsockopt_string(zmq.CURVE_PUBLICKEY, keys[0])
            s.setsockopt_string(zmq.CURVE_SECRETKEY, keys[1])

    control = ctx.socket(zmq.DEALER)
    curve_client(control, keys[2] if keys else None)
    if a.mode != "no_routing_id":
        control.setsockopt(zmq.ROUTING_ID, a.name.encode())
    control.setsockopt(zmq.LINGER, 500)
    control.connect(a.director)
    data = ctx.socket(zmq.ROUTER)
    data.setsockopt(zmq.LINGER, 0)
    if keys:
        data.setsockopt(zmq.CURVE_SERVER, 1)
        data.setsockopt_string(zmq.CURVE_SECRETKEY, keys[1])
        data.setsockopt_string(zmq.ZAP_DOMAIN, "lightfarm")
    data.bind(a.bind)
    inputs = []
    waiting = {}  # our request id -> (peer, their id, n)
    next_id = [1]

    def header(t, op="", id=0):
        return msgpack.packb({"v": version, "t": t, "id": id, "s": a.name, "op": op, "q": 0})

    def send(t, op="", body=None):
        control.send_multipart([header(t, op), msgpack.packb(body)])

    def reply(peer, id, n, radiance):
        told = n + 1 if a.mode == "wrong_n" else n
        data.send_multipart([peer, header(REPLY, id=id), msgpack.packb({"n": told, "L": radiance})])

    def refuse(peer, id, code, message):
        data.send_multipart([peer, header(ERROR, id=id), msgpack.packb({"code": code, "message": message})])

    send(HELLO, body={"kind": a.kind, "pid": os.getpid(), "float_format": "f32le",
                      "endpoint": data.getsockopt_string(zmq.LAST_ENDPOINT)})
    last, timeout, next_beat = time.monotonic(), 10.0, 0.0
    while time.monotonic() - last < timeout:
        if time.monotonic() >= next_beat:
            send(HEARTBEAT)
            next_beat = time.monotonic() + min(1.0, timeout / 4)
        while keys and zap.poll(0):  # ZAP: only the farm's keys
            f = zap.recv_multipart()
            ok = f[5] == b"CURVE" and zmq.utils.z85.encode(f[6]).decode() in keys[3]
            zap.send_multipart([f[0], f[1], b"200" if ok else b"400", b"", b"", b""])
        if control.poll(20):
            h, body = (msgpack.unpackb(f, raw=False) for f in control.recv_multipart())
            last = time.monotonic()
            if h["t"] == CONFIG:
                timeout = float(body.get("heartbeat_timeout", 10.0))
                for spec in body.get("inputs") or []:
                    s = ctx.socket(zmq.DEALER)
                    s.setsockopt(zmq.ROUTING_ID, a.name.encode())
                    s.setsockopt(zmq.LINGER, 0)
                    curve_client(s, spec.get("key"))
                    s.connect(spec["endpoint"])
                    inputs.append(s)
                send(READY, "configure", {"phase": "configure"})
            elif h["t"] == PHASE and h["op"] == "setup":
                send(READY, "setup", {"phase": "setup"})
            elif h["t"] == PHASE and h["op"] == "render":
                if a.mode != "no_ready_render":
                    send(READY, "render", {"phase": "render"})
            elif h["t"] == PHASE and h["op"] == "frame":
                if a.mode != "no_ready_frame":
                    send(READY, "frame", {"phase": "frame"})
            elif h["t"] == BYE or (h["t"] == PHASE and h["op"] == "finish"):
                if a.mode == "crash_at_finish":
                    return 3
                send(STATS, body={})
                send(BYE)
                return 0
        while data.poll(0):
            frames = data.recv_multipart()
            peer = frames[0]
            if a.mode == "crash":
                return 3
            if a.mode == "silent":
                continue
            try:
                if len(frames) != 3:
                    raise ValueError("expected 2 frames")
                h = msgpack.unpackb(frames[1], raw=False)
                body = msgpack.unpackb(frames[2], raw=False)
                if not isinstance(h, dict) or h.get("v") != 1:
                    raise ValueError("bad header")
            except Exception as e:
                if a.mode != "silent_on_malformed":
                    refuse(peer, 0, "bad_message", str(e))
                continue
            if h.get("t") != REQUEST or h.get("op") != "shade":
                refuse(peer, h.get("id", 0), "unknown_op", "serves only 'shade'")
                continue
            n = body.get("n", 0)
            if a.mode == "slow":
                time.sleep(0.35)
            if inputs and a.mode != "ignore_input":
                rid = next_id[0]
                next_id[0] += 1
                waiting[rid] = (peer, h["id"], n)
                inputs[0].send_multipart([header(REQUEST, "shade", rid), frames[2]])
            else:
                reply(peer, h["id"], n, struct.pack("<%df" % (3 * n), *([0.25] * (3 * n))))
        for s in inputs:
            while s.poll(0):
                h, body = (msgpack.unpackb(f, raw=False) for f in s.recv_multipart())
                if h.get("id") in waiting:
                    peer, id, n = waiting.pop(h["id"])
                    reply(peer, id, n, body.get("L", b""))
    return 3


if __name__ == "__main__":
    sys.exit(main())
