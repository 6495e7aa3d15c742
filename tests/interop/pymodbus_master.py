#!/usr/bin/env python3
"""pymodbus as the master of our simulated Yaskawa V7 (tests/tests/cross_crate/interop_masters.rs).

    pymodbus_master.py (--tcp HOST:PORT | --serial PATH) [--slave 1] [--baud 9600] [--ascii]

--ascii: Modbus ASCII frames (':' ... LRC CR LF) instead of RTU on --serial, or instead of
Modbus TCP's MBAP on --tcp (ASCII frames over TCP, as a transparent gateway forwards them).
--bytesize 7|8 and --parity N|E|O set the serial line's character (default 8, N).

Runs the scenario below and prints one JSON object per step on stdout:
{"step": ..., "values": [...]} for data, {"step": ..., "exception": code} for an exception
response, {"step": ..., "error": "..."} for anything else. The Rust test judges the results.
"""

import argparse
import json
import logging
import sys

from pymodbus import FramerType
from pymodbus.client import ModbusSerialClient, ModbusTcpClient


def report(step, result=None, **extra):
    line = {"step": step, **extra}
    if result is not None:
        if result.isError():
            code = getattr(result, "exception_code", None)
            if code is None:
                line["error"] = str(result)
            else:
                line["exception"] = int(code)
        elif hasattr(result, "registers"):
            line["values"] = list(result.registers)
        else:
            line["ok"] = True
    print(json.dumps(line), flush=True)


def run(step, call):
    try:
        report(step, call())
    except Exception as e:  # the test reports the step that failed and why
        report(step, error=f"{type(e).__name__}: {e}")


def main():
    parser = argparse.ArgumentParser()
    link = parser.add_mutually_exclusive_group(required=True)
    link.add_argument("--tcp", metavar="HOST:PORT")
    link.add_argument("--serial", metavar="PATH")
    parser.add_argument("--slave", type=int, default=1)
    parser.add_argument("--baud", type=int, default=9600)
    parser.add_argument("--ascii", action="store_true")
    parser.add_argument("--bytesize", type=int, choices=[7, 8], default=8)
    parser.add_argument("--parity", choices=["N", "E", "O"], default="N")
    args = parser.parse_args()
    logging.basicConfig(level=logging.CRITICAL, stream=sys.stderr)
    if args.tcp:
        host, port = args.tcp.rsplit(":", 1)
        framer = FramerType.ASCII if args.ascii else FramerType.SOCKET
        client = ModbusTcpClient(host, port=int(port), framer=framer, timeout=1, retries=0)
    else:
        client = ModbusSerialClient(
            args.serial,
            framer=FramerType.ASCII if args.ascii else FramerType.RTU,
            baudrate=args.baud,
            parity=args.parity,
            stopbits=1,
            bytesize=args.bytesize,
            timeout=1,
            retries=0,
        )
    if not client.connect():
        report("connect", error="cannot connect")
        return 1
    s = args.slave
    # Status signal 1, fault content, data link status, frequency reference monitor.
    run("read", lambda: client.read_holding_registers(0x0020, count=4, device_id=s))
    # 06h: frequency reference 30.0 Hz (n152 = 0: 0.1 Hz), read back through its monitor.
    run("write_single", lambda: client.write_register(0x0002, 300, device_id=s))
    run("read_back", lambda: client.read_holding_registers(0x0023, count=1, device_id=s))
    # n019 accel time 6000.1 s: out of range, 21h.
    run("out_of_range", lambda: client.write_register(0x0113, 60001, device_id=s))
    # Nothing at 0600h; ENTER 0900h is write-only: both 02h.
    run("unknown_register", lambda: client.read_holding_registers(0x0600, count=1, device_id=s))
    run("write_only", lambda: client.read_holding_registers(0x0900, count=1, device_id=s))
    # 10h: run forward at 45.0 Hz, then status shows during run.
    run("write_multiple", lambda: client.write_registers(0x0001, [0x0001, 450], device_id=s))
    run("status_running", lambda: client.read_holding_registers(0x0020, count=1, device_id=s))
    # A stopped-only parameter while running: 22h.
    run("while_running", lambda: client.write_register(0x0113, 50, device_id=s))
    # 08h loop-back (sub-function 0000h).
    run("loop_back", lambda: loop_back(client, s))
    # Broadcast (slave 0): stop, 15000 = 50 % of n011 = 30.0 Hz; no reply is awaited.
    run(
        "broadcast",
        lambda: client.write_registers(
            0x0001, [0x0000, 15000], device_id=0, no_response_expected=True
        ),
    )
    run("status_after_broadcast", lambda: client.read_holding_registers(0x0020, count=1, device_id=s))
    client.close()
    return 0


def loop_back(client, slave):
    r = client.diag_query_data(b"\xa5\x37", device_id=slave)
    if r.isError():
        return r
    data = r.message
    if isinstance(data, (bytes, bytearray)):
        value = int.from_bytes(bytes(data)[:2], "big")
    else:
        value = int(data)

    class Echo:
        registers = [value]

        def isError(self):
            return False

    return Echo()


if __name__ == "__main__":
    sys.exit(main())
