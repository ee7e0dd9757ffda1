#!/usr/bin/python3
"""tint — a lightfarm LightOp in Python, written from docs/PROTOCOL.md with only pyzmq and msgpack.

With an input, it asks the input for the light at each point and multiplies it by `color`.
Without one, it paints surface normals as colour: (normal + 1) / 2 * scale.

Parameters (from the farm script): color = {r, g, b} (default {1, 1, 1}), scale (default 1).
Run by the farm as:  ./tint.py --kind exec --name NAME --director ENDPOINT [--bind ENDPOINT] [--curve]
"""
import argparse
import os
import struct
import sys
import time

import msgpack
import zmq
import zmq.utils.z85

PROTOCOL = 1
HELLO, CONFIG, PHASE, REQUEST, REPLY, ERROR, STATS, HEARTBEAT, BYE, READY, PEER_DOWN = range(1, 12)


class Actor:
    def __init__(self, kind, name, director, bind, keys=None):
        self.kind, self.name = kind, name
        self.ctx = zmq.Context()
        # CURVE (--curve): keys = (own public, own secret, director public, {every public key of the farm}).
        self.keys = keys
        self.zap = None
        if keys:
            self.zap = self.ctx.socket(zmq.REP)  # ZeroMQ asks it about every client of our data socket
            self.zap.bind("inproc://zeromq.zap.01")
        self.control = self.ctx.socket(zmq.DEALER)
        self.control.setsockopt(zmq.ROUTING_ID, name.encode())
        if keys:
            self.curve_client(self.control, keys[2])
        self.control.setsockopt(zmq.LINGER, 1000)
        self.control.connect(director)
        self.data = self.ctx.socket(zmq.ROUTER)
        if keys:
            self.data.setsockopt(zmq.CURVE_SERVER, 1)
            self.data.setsockopt_string(zmq.CURVE_SECRETKEY, keys[1])
            self.data.setsockopt_string(zmq.ZAP_DOMAIN, "lightfarm")
        self.data.setsockopt(zmq.LINGER, 0)
        self.data.bind(bind)
        self.endpoint = self.data.getsockopt_string(zmq.LAST_ENDPOINT)
        self.input = None            # DEALER to our input, if the script wired one
        self.next_id = 1
        self.waiting = {}            # our request id to the input -> (client routing id, client's request id)
        self.color, self.scale = (1.0, 1.0, 1.0), 1.0
        self.heartbeat_timeout = 10.0
        self.requests = self.points = 0

    # --- the wire -----------------------------------------------------------------------------------------
    def curve_client(self, socket, server_key):
        socket.setsockopt_string(zmq.CURVE_SERVERKEY, server_key)
        socket.setsockopt_string(zmq.CURVE_PUBLICKEY, self.keys[0])
        socket.setsockopt_string(zmq.CURVE_SECRETKEY, self.keys[1])

    def on_zap(self):
        """ZAP: let in a CURVE client only if its key is one of the farm's."""
        frames = self.zap.recv_multipart()
        version, request_id, mechanism = frames[0], frames[1], frames[5]
        allowed = mechanism == b"CURVE" and len(frames) > 6 and zmq.utils.z85.encode(frames[6]).decode() in self.keys[3]
        self.zap.send_multipart([version, request_id, b"200" if allowed else b"400",
                                 b"OK" if allowed else b"not a key of this farm", b"", b""])

    def header(self, t, id=0, op="", q=0):
        return msgpack.packb({"v": PROTOCOL, "t": t, "id": id, "s": self.name, "op": op, "q": q})

    def to_director(self, t, op="", body=None, id=0):
        self.control.send_multipart([self.header(t, id, op), msgpack.packb(body)])

    def reply(self, peer, id, body, t=REPLY):
        self.data.send_multipart([peer, self.header(t, id, q=len(self.waiting)), msgpack.packb(body)])

    def error(self, peer, id, code, message):
        self.reply(peer, id, {"code": code, "message": message}, t=ERROR)

    @staticmethod
    def decode(frames):
        """(header, body) or raises ValueError with what is wrong."""
        if len(frames) != 2:
            raise ValueError("expected 2 frames (header, body), got %d" % len(frames))
        try:
            header = msgpack.unpackb(frames[0], raw=False)
            body = msgpack.unpackb(frames[1], raw=False)
        except Exception as e:  # any malformed bytes
            raise ValueError("not valid msgpack (%s)" % e)
        if not isinstance(header, dict) or header.get("v") != PROTOCOL or not isinstance(header.get("t"), int):
            raise ValueError("bad header (protocol version %r, expected %d)" % (
                header.get("v") if isinstance(header, dict) else None, PROTOCOL))
        return header, body if isinstance(body, dict) else {}

    # --- the algorithm ------------------------------------------------------------------------------------
    def shade_alone(self, body):
        n = body["n"]
        normals = struct.unpack("<%df" % (3 * n), body["nrm"])
        out = [(c + 1.0) * 0.5 * self.scale for c in normals]
        return struct.pack("<%df" % (3 * n), *out)

    def tinted(self, radiance, n):
        values = struct.unpack("<%df" % (3 * n), radiance)
        r, g, b = self.color
        out = []
        for i in range(n):
            out += (values[3 * i] * r, values[3 * i + 1] * g, values[3 * i + 2] * b)
        return struct.pack("<%df" % (3 * n), *out)

    # --- handlers -----------------------------------------------------------------------------------------
    def on_config(self, body):
        params = body.get("params") or {}
        self.color = tuple(float(c) for c in params.get("color", (1, 1, 1)))
        self.scale = float(params.get("scale", 1.0))
        if len(self.color) != 3:
            raise ValueError("tint: parameter 'color' must be a list of 3 numbers")
        self.heartbeat_timeout = float(body.get("heartbeat_timeout", 10.0))
        inputs = body.get("inputs") or []
        if len(inputs) > 1:
            raise ValueError("tint takes at most one input")
        if inputs:
            self.input = self.ctx.socket(zmq.DEALER)
            self.input.setsockopt(zmq.ROUTING_ID, self.name.encode())
            if self.keys:
                self.curve_client(self.input, inputs[0]["key"])
            self.input.setsockopt(zmq.LINGER, 0)
            self.input.connect(inputs[0]["endpoint"])

    def on_request(self, peer, header, body):
        if header["t"] != REQUEST or header.get("op") != "shade":
            return self.error(peer, header.get("id", 0), "unknown_op", "tint serves only 'shade'")
        n, nrm = body.get("n"), body.get("nrm")
        if not isinstance(n, int) or n < 0 or not isinstance(nrm, bytes) or len(nrm) != 12 * n:
            return self.error(peer, header["id"], "bad_request", "shade request: 'n' and 'nrm' do not agree")
        self.requests += 1
        self.points += n
        if self.input is None:
            return self.reply(peer, header["id"], {"n": n, "L": self.shade_alone(body)})
        # Ask our input for the same points, asynchronously; answer when it answers.
        rid = self.next_id
        self.next_id += 1
        self.waiting[rid] = (peer, header["id"], n)
        self.input.send_multipart([self.header(REQUEST, rid, "shade"), msgpack.packb(body)])

    def on_input_reply(self, header, body):
        pending = self.waiting.pop(header.get("id"), None)
        if pending is None:
            return  # not ours, or answered already
        peer, client_id, n = pending
        if header["t"] == ERROR:
            return self.error(peer, client_id, "shade_failed", "input: %s" % body.get("message"))
        radiance = body.get("L")
        if not isinstance(radiance, bytes) or len(radiance) != 12 * n:
            return self.error(peer, client_id, "shade_failed", "input answered the wrong number of values")
        self.reply(peer, client_id, {"n": n, "L": self.tinted(radiance, n)})

    # --- the loop -----------------------------------------------------------------------------------------
    def run(self):
        self.to_director(HELLO, body={"kind": self.kind, "pid": os.getpid(), "endpoint": self.endpoint,
                                      "float_format": "f32le"})
        last_from_director = time.monotonic()
        next_beat = 0.0
        while True:
            poller = zmq.Poller()
            poller.register(self.control, zmq.POLLIN)
            poller.register(self.data, zmq.POLLIN)
            if self.input is not None:
                poller.register(self.input, zmq.POLLIN)
            if self.zap is not None:
                poller.register(self.zap, zmq.POLLIN)
            ready = dict(poller.poll(100))
            if self.zap is not None and self.zap in ready:
                self.on_zap()
            now = time.monotonic()
            if self.control in ready:
                while self.control.poll(0):
                    try:
                        header, body = self.decode(self.control.recv_multipart())
                    except ValueError as e:
                        print("%s: dropped a bad message from the director: %s" % (self.name, e), file=sys.stderr)
                        continue
                    last_from_director = now
                    t, op = header["t"], header.get("op", "")
                    if t == CONFIG:
                        try:
                            self.on_config(body)
                        except (ValueError, TypeError, KeyError) as e:
                            self.to_director(ERROR, body={"code": "actor_failed", "message": str(e)})
                            return 1
                        self.to_director(READY, "configure", {"phase": "configure"})
                    elif (t == PHASE and op == "finish") or t == BYE:
                        self.to_director(STATS, body={"requests": self.requests, "points": self.points})
                        self.to_director(BYE)
                        return 0
                    elif t == PHASE:
                        # Every other phase (setup, render, a job's frame) is answered at once: tint keeps nothing
                        # that depends on the phase or the view.
                        self.to_director(READY, op, {"phase": op})
            if self.data in ready:
                while self.data.poll(0):
                    frames = self.data.recv_multipart()
                    peer, rest = frames[0], frames[1:]
                    try:
                        header, body = self.decode(rest)
                    except ValueError as e:
                        self.error(peer, 0, "bad_message", str(e))  # refuse it and carry on
                        continue
                    try:
                        self.on_request(peer, header, body)
                    except (KeyError, TypeError, struct.error) as e:
                        self.error(peer, header.get("id", 0), "bad_request", "malformed shade request (%s)" % e)
            if self.input is not None and self.input in ready:
                while self.input.poll(0):
                    try:
                        header, body = self.decode(self.input.recv_multipart())
                    except ValueError:
                        continue
                    self.on_input_reply(header, body)
            if now >= next_beat:
                self.to_director(HEARTBEAT)
                next_beat = now + min(1.0, self.heartbeat_timeout / 4)
            if now - last_from_director > self.heartbeat_timeout:
                print("%s: the director is gone; stopping" % self.name, file=sys.stderr)
                return 3


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", required=True)
    parser.add_argument("--name", required=True)
    parser.add_argument("--director", required=True)
    parser.add_argument("--bind", default="tcp://127.0.0.1:*")  # given when the farm spans hosts
    parser.add_argument("--curve", action="store_true")  # the farm's keys come on the first line of stdin
    args = parser.parse_args()
    keys = None
    if args.curve:
        words = sys.stdin.readline().split()
        if len(words) < 5 or words[0] != "LFKEYS1":
            print("%s: --curve: no keys on standard input" % args.name, file=sys.stderr)
            return 2
        keys = (words[1], words[2], words[3], set(words[4:]))
    actor = Actor(args.kind, args.name, args.director, args.bind, keys)
    try:
        code = actor.run()
    except KeyboardInterrupt:
        code = 130
    actor.ctx.destroy(linger=500)
    return code


if __name__ == "__main__":
    sys.exit(main())
