"""Validates `modbus:` YAML files with Home Assistant's own configuration schema: the modbus
integration's CONFIG_SCHEMA, its final check included (which drops duplicate entities and warns
about short scan intervals). Prints one line per file; exits 1 if any file is refused, loses an
entity or makes the integration log a warning.

Usage: ha_check_modbus.py FILE.yaml...  (run with target/ha-venv/bin/python)
"""
import logging
import sys

import yaml

warnings = []


class Catch(logging.Handler):
    def emit(self, record):
        warnings.append(record.getMessage())


logging.getLogger("homeassistant.components.modbus").addHandler(Catch(level=logging.WARNING))

from homeassistant.components.modbus import CONFIG_SCHEMA  # noqa: E402
from homeassistant.const import __version__  # noqa: E402

failed = False
for path in sys.argv[1:]:
    warnings.clear()
    with open(path, encoding="utf-8") as f:
        # libyaml's loader, as Home Assistant's own YAML loader uses when it is there (the
        # pure-Python one took most of this check's time on the larger maps).
        conf = yaml.load(f, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    given = sum(len(h.get("sensors", [])) + len(h.get("binary_sensors", [])) for h in conf["modbus"])
    try:
        out = CONFIG_SCHEMA(conf)
    except Exception as e:  # voluptuous.Invalid and its kin
        print(f"{path}: REFUSED by Home Assistant {__version__}: {e}")
        failed = True
        continue
    kept = sum(len(h.get("sensors", [])) + len(h.get("binary_sensors", [])) for h in out["modbus"])
    for w in warnings:
        print(f"{path}: warning: {w}")
    ok = not warnings and kept == given
    failed |= not ok
    print(f"{path}: {'ok' if ok else 'NOT OK'}: Home Assistant {__version__} keeps {kept} of {given} sensors and binary sensors")
sys.exit(1 if failed else 0)
