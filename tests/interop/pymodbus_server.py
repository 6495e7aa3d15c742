#!/usr/bin/env python3
"""A Modbus slave made with pymodbus (code nobody on this project wrote), for our client to talk
to in tests/tests/cross_crate/interop_client.rs.

Device 1:
  - holding registers 0-99 hold 1000 + address; input registers 0-9 hold 2000 + address;
  - reading or writing outside them answers exception 02h (pymodbus: illegal address);
  - writing a value above 50000 answers exception 03h (illegal value), written by a device action;
  - a read starting at holding register 50 is answered only after 1.5 s (the client times out,
    and must discard the late reply when it comes).

    pymodbus_server.py --tcp PORT
    pymodbus_server.py --serial PATH [--baud 19200]

Prints "ready" on stdout once serving; runs until killed.
"""

import argparse
import asyncio
import logging
import sys

from pymodbus.constants import ExcCodes
from pymodbus.server import ModbusSerialServer, ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

LIMIT = 50000
SLOW = 50


async def action(function_code, start_address, address, count, current_registers, set_values):
    """Device action: a write of a value above LIMIT is refused with 03h; a read starting at
    SLOW is answered late."""
    if set_values is not None and any(int(v) > LIMIT for v in set_values):
        return ExcCodes.ILLEGAL_VALUE
    if set_values is None and function_code == 3 and address == SLOW:
        await asyncio.sleep(1.5)
    return None


def device():
    holding = [SimData(address=0, values=[1000 + a for a in range(100)], datatype=DataType.REGISTERS)]
    inputs = [SimData(address=0, values=[2000 + a for a in range(10)], datatype=DataType.REGISTERS)]
    coils = [SimData(address=0, values=[False] * 16, datatype=DataType.BITS)]
    discrete = [SimData(address=0, values=[False] * 16, datatype=DataType.BITS)]
    return SimDevice(
        id=1,
        simdata=(coils, discrete, holding, inputs),
        action=action,
    )


async def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    link = parser.add_mutually_exclusive_group(required=True)
    link.add_argument("--tcp", type=int, metavar="PORT")
    link.add_argument("--serial", metavar="PATH")
    parser.add_argument("--baud", type=int, default=19200)
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR, stream=sys.stderr)
    if args.tcp is not None:
        server = ModbusTcpServer(device(), address=("127.0.0.1", args.tcp))
    else:
        server = ModbusSerialServer(
            device(),
            port=args.serial,
            baudrate=args.baud,
            parity="N",
            stopbits=1,
            bytesize=8,
        )
    await server.serve_forever(background=True)
    print("ready", flush=True)
    await asyncio.Event().wait()


if __name__ == "__main__":
    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        pass
