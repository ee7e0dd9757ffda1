#!/usr/bin/python3
"""An actor that gets the protocol wrong on purpose, for tests of check-actor and of the director.

  --mode wrong_version   says HELLO with protocol version 2
  --mode silent          does everything right but never answers a shade request
  --mode crash           exits with status 3 on its first shade request
"""
import argparse
import os
import sys
import time

import msgpack
import zmq

HELLO, CONFIG, PHASE, REQUEST, REPLY, ERROR, STATS, HEARTBEAT, BYE, READY = range(1, 11)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--mode", required=True, choices=["wrong_version", "silent", "crash"])
    p.add_argument("--kind", required=True)
    p.add_argument("--name", required=True)
    p.add_argument("--director", required=True)
    a = p.parse_args()
    version = 2 if a.mode == "wrong_version" else 1
    ctx = zmq.Context()
    control = ctx.socket(zmq.DEALER)
    control.setsockopt(zmq.ROUTING_ID, a.name.encode())
    control.setsockopt(zmq.LINGER, 0)
    control.connect(a.director)
    data = ctx.socket(zmq.ROUTER)
    data.setsockopt(zmq.LINGER, 0)
    data.bind("tcp://127.0.0.1:*")

    def send(t, op="", body=None):
        control.send_multipart([msgpack.packb({"v": version, "t": t, "id": 0, "s": a.name, "op": op, "q": 0}),
                                msgpack.packb(body)])

    send(HELLO, body={"kind": a.kind, "pid": os.getpid(), "float_format": "f32le",
                      "endpoint": data.getsockopt_string(zmq.LAST_ENDPOINT)})
    last, timeout = time.monotonic(), 10.0
    while time.monotonic() - last < timeout:
        send(HEARTBEAT)
        if control.poll(200):
            header, body = (msgpack.unpackb(f, raw=False) for f in control.recv_multipart())
            last = time.monotonic()
            if header["t"] == CONFIG:
                timeout = float(body.get("heartbeat_timeout", 10.0))
                send(READY, "configure", {"phase": "configure"})
            elif header["t"] == PHASE and header["op"] in ("setup", "render"):
                send(READY, header["op"], {"phase": header["op"]})
            elif header["t"] == BYE or (header["t"] == PHASE and header["op"] == "finish"):
                send(STATS, body={})
                send(BYE)
                return 0
        while data.poll(0):
            data.recv_multipart()
            if a.mode == "crash":
                return 3
            # silent: drop it
    return 0


if __name__ == "__main__":
    sys.exit(main())
