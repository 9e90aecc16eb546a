"""Stand-in for the `zenohd` router of the eclipse/zenoh image, for machines that reach no image registry.

It is a real Zenoh router (zenoh-python in router mode, the same Rust core as zenohd) and takes the
zenohd arguments docker-compose.yml passes. What it does not have: zenohd's plugins, so the REST API
(`--rest-http-port`) is not served; it says so at start.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading

import zenoh


def main() -> int:
    parser = argparse.ArgumentParser(prog="zenohd (stand-in)")
    parser.add_argument("-l", "--listen", action="append", default=[])
    parser.add_argument("-e", "--connect", action="append", default=[])
    parser.add_argument("--rest-http-port", default=None)
    parser.add_argument("--no-multicast-scouting", action="store_true")
    args = parser.parse_args()
    listen = args.listen or ["tcp/[::]:7447"]
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps("router"))
    conf.insert_json5("listen/endpoints", json.dumps(listen))
    if args.connect:
        conf.insert_json5("connect/endpoints", json.dumps(args.connect))
    if args.no_multicast_scouting:
        conf.insert_json5("scouting/multicast/enabled", "false")
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    session = zenoh.open(conf)
    print(f"stand-in zenohd (zenoh-python {zenoh.__version__ if hasattr(zenoh, '__version__') else '?'} "
          f"in router mode) listening on {','.join(listen)}", flush=True)
    if args.rest_http_port:
        print(f"stand-in zenohd: no REST plugin, port {args.rest_http_port} is not served", flush=True)
    while not stop.wait(0.5):
        pass
    session.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
