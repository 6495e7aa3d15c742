#!/usr/bin/env python3
"""minimalmodbus as the master of our simulated Yaskawa V7 (tests/tests/cross_crate/interop_masters.rs).

minimalmodbus speaks Modbus RTU only; over TCP it sends RTU frames through a pyserial
`socket://` URL, as to a transparent serial gateway.

    minimalmodbus_master.py (--serial PATH | --rtu-tcp HOST:PORT) [--slave 1] [--baud 9600]

Same scenario and output as pymodbus_master.py: one JSON object per step.
"""

import argparse
import json
import sys

import minimalmodbus
import serial

# minimalmodbus names the standard codes by message; anything else it reports with its number.
MESSAGES = {
    "Slave reported illegal function": 0x01,
    "Slave reported illegal data address": 0x02,
    "Slave reported illegal data value": 0x03,
    "Slave reported device failure": 0x04,
    "Slave reported device busy": 0x06,
}


def run(step, call):
    line = {"step": step}
    try:
        result = call()
        if result is None:
            line["ok"] = True
        else:
            line["values"] = list(result)
    except minimalmodbus.SlaveReportedException as e:
        text = str(e)
        if text in MESSAGES:
            line["exception"] = MESSAGES[text]
        elif text.startswith("Slave reported error code "):
            line["exception"] = int(text.rsplit(" ", 1)[1])
        else:
            line["error"] = text
    except Exception as e:  # the test reports the step that failed and why
        line["error"] = f"{type(e).__name__}: {e}"
    print(json.dumps(line), flush=True)


def instrument(args, slave):
    if args.serial:
        inst = minimalmodbus.Instrument(args.serial, slave)
        inst.serial.baudrate = args.baud
        inst.serial.parity = serial.PARITY_NONE
    else:
        # minimalmodbus takes any open pyserial object: here a TCP socket by URL.
        inst = minimalmodbus.Instrument(serial.serial_for_url(f"socket://{args.rtu_tcp}"), slave)
    inst.serial.timeout = 1.0
    inst.clear_buffers_before_each_transaction = True
    return inst


def main():
    parser = argparse.ArgumentParser()
    link = parser.add_mutually_exclusive_group(required=True)
    link.add_argument("--serial", metavar="PATH")
    link.add_argument("--rtu-tcp", metavar="HOST:PORT")
    parser.add_argument("--slave", type=int, default=1)
    parser.add_argument("--baud", type=int, default=9600)
    args = parser.parse_args()
    drive = instrument(args, args.slave)
    run("read", lambda: drive.read_registers(0x0020, 4))
    run("write_single", lambda: drive.write_register(0x0002, 300, functioncode=6))
    run("read_back", lambda: drive.read_registers(0x0023, 1))
    run("out_of_range", lambda: drive.write_register(0x0113, 60001, functioncode=6))
    run("unknown_register", lambda: drive.read_registers(0x0600, 1))
    run("write_only", lambda: drive.read_registers(0x0900, 1))
    run("write_multiple", lambda: drive.write_registers(0x0001, [0x0001, 450]))
    run("status_running", lambda: drive.read_registers(0x0020, 1))
    run("while_running", lambda: drive.write_register(0x0113, 50, functioncode=6))
    # 08h loop-back: minimalmodbus has no public call for it; its command primitive sends
    # sub-function 0000h and the data, and checks the echo.
    run("loop_back", lambda: [int.from_bytes(drive._perform_command(8, b"\x00\x00\xa5\x37")[2:4], "big")])
    # Broadcast (slave address 0): minimalmodbus sends and does not wait for a reply.
    drive.address = 0
    run("broadcast", lambda: drive.write_registers(0x0001, [0x0000, 15000]))
    drive.address = args.slave
    run("status_after_broadcast", lambda: drive.read_registers(0x0020, 1))
    drive.serial.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
