#!/usr/bin/env bash
# Installs the third-party Modbus peers the interop tests (tests/tests/interop_*.rs) talk to.
# Idempotent: installs only what is missing.
#
# - Debian packages mbpoll and socat, with apt-get when running as root (otherwise prints the
#   command to run);
# - for the bridge tests (cli/tests/cli/bridge.rs) prometheus, mosquitto, mosquitto-clients and
#   openssl, without their recommendations (prometheus recommends node-exporter and more);
# - Node-RED and node-red-contrib-modbus from npm under target/interop-node (the Node-RED export's
#   test, cli/tests/cli/export_node_red.rs), pinned: node-red-contrib-modbus 5.23.3 is the newest the
#   registry serves that runs on Debian's Node.js 20 (5.60 needs Node 22) and installs from npm
#   alone (5.45 fetches a dependency from another host); ~25 s on an empty npm cache;
# - Home Assistant 2024.3.3 in a venv of its own at target/ha-venv, for the check of the Home
#   Assistant export against the modbus integration's own schema (tests/interop/ha_check_modbus.py):
#   2024.3 is the last release for Python 3.11, its modbus integration pins pymodbus 3.6.6 (the
#   interop venv pins 3.16.1), and a full `pip install homeassistant` resolves hundreds of
#   packages (14 min here), so it is installed --no-deps with the modules its modbus schema
#   imports (~1.5 min);
# - Python packages pymodbus, minimalmodbus and pyserial in a venv at target/interop-venv, at the
#   versions the scripts in tests/interop/ are written for (pymodbus changes its API between
#   minor versions), and jsonschema, which cli/tests/cli/machine_output.rs checks the CLI's JSON
#   output with (docs/schema/), and fpdf2, which cli/tests/cli/import.rs writes PDF manuals with;
# - poppler-utils (pdftotext), which `drivemap import --manual x.pdf` extracts a PDF's text with.
set -euo pipefail
cd "$(dirname "$0")/../.."

missing=()
for tool in mbpoll socat npm; do
  command -v "$tool" >/dev/null 2>&1 || missing+=("$tool")
done
bare=()
for pair in prometheus:prometheus mosquitto:mosquitto mosquitto_sub:mosquitto-clients openssl:openssl pdftotext:poppler-utils; do
  PATH="$PATH:/usr/sbin:/sbin" command -v "${pair%%:*}" >/dev/null 2>&1 || bare+=("${pair#*:}")
done
if [ $((${#missing[@]} + ${#bare[@]})) -gt 0 ]; then
  if [ "$(id -u)" = 0 ]; then
    echo "== apt-get install -y ${missing[*]} ${bare[*]}"
    apt-get update -qq
    if [ ${#missing[@]} -gt 0 ]; then
      packages=("${missing[@]/npm/nodejs npm}")
      # shellcheck disable=SC2068 # "nodejs npm" is two packages
      DEBIAN_FRONTEND=noninteractive apt-get install -y -qq ${packages[@]} >/dev/null
    fi
    if [ ${#bare[@]} -gt 0 ]; then
      DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${bare[@]}" >/dev/null
    fi
  else
    echo "missing ${missing[*]} ${bare[*]}: run as root: apt-get install -y ${missing[*]} ${bare[*]}" >&2
  fi
fi

venv=target/interop-venv
python=${PYTHON:-python3}
if [ ! -x "$venv/bin/python" ] || [ ! -x "$venv/bin/pip" ]; then
  echo "== $python -m venv $venv"
  "$python" -m venv --clear "$venv"
fi
pins=(pymodbus==3.16.1 minimalmodbus==2.1.1 pyserial==3.5 jsonschema==4.26.0 fpdf2==2.8.9)
check='import pymodbus, minimalmodbus, serial, importlib.metadata
assert (pymodbus.__version__, minimalmodbus.__version__, serial.__version__) == ("3.16.1", "2.1.1", "3.5")
assert importlib.metadata.version("jsonschema") == "4.26.0"
assert importlib.metadata.version("fpdf2") == "2.8.9"'
if ! "$venv/bin/python" -c "$check" >/dev/null 2>&1; then
  echo "== $venv/bin/pip install ${pins[*]}"
  "$venv/bin/pip" install --quiet --disable-pip-version-check "${pins[@]}"
fi
"$venv/bin/python" -c 'import pymodbus, minimalmodbus, serial, importlib.metadata; print("interop peers: pymodbus", pymodbus.__version__, "minimalmodbus", minimalmodbus.__version__, "pyserial", serial.__version__, "jsonschema", importlib.metadata.version("jsonschema"))'
echo "interop peers: $(command -v mbpoll || echo 'mbpoll MISSING') $(command -v socat || echo 'socat MISSING')"
echo "bridge tools: $(command -v prometheus || echo 'prometheus MISSING') $(PATH="$PATH:/usr/sbin" command -v mosquitto || echo 'mosquitto MISSING') $(command -v mosquitto_sub || echo 'mosquitto-clients MISSING') $(command -v openssl || echo 'openssl MISSING')"

node_dir=target/interop-node
node_pins=(node-red@4.1.15 node-red-contrib-modbus@5.23.3)
node_check="const v = (m) => require(process.cwd() + '/$node_dir/node_modules/' + m + '/package.json').version;
if (v('node-red') !== '4.1.15' || v('node-red-contrib-modbus') !== '5.23.3') process.exit(1);"
if command -v npm >/dev/null 2>&1; then
  if ! node -e "$node_check" >/dev/null 2>&1; then
    echo "== npm install ${node_pins[*]} (in $node_dir)"
    mkdir -p "$node_dir"
    (cd "$node_dir" && npm install --no-audit --no-fund --loglevel=error --no-save "${node_pins[@]}")
  fi
  echo "Node-RED: $(node -e "console.log(require(process.cwd() + '/$node_dir/node_modules/node-red/package.json').version)" 2>/dev/null || echo MISSING), node-red-contrib-modbus $(node -e "console.log(require(process.cwd() + '/$node_dir/node_modules/node-red-contrib-modbus/package.json').version)" 2>/dev/null || echo MISSING)"
else
  echo "Node-RED: npm MISSING (apt-get install -y nodejs npm)" >&2
fi

ha_venv=target/ha-venv
ha_pins=(homeassistant==2024.3.3 pymodbus==3.6.6 PyYAML==6.0.1 voluptuous==0.13.1 voluptuous-serialize==2.6.0
  yarl==1.9.4 idna==3.20 multidict==6.9.1 python-slugify==8.0.4 text-unidecode==1.3 ciso8601==2.3.1
  orjson==3.9.15 atomicwrites-homeassistant==1.4.1 aiohttp==3.9.3 attrs==23.2.0 aiosignal==1.4.0
  frozenlist==1.8.0 typing_extensions==4.16.0 ulid-transform==0.9.0 awesomeversion==24.2.0
  async-interrupt==1.1.1 Jinja2==3.1.3 MarkupSafe==3.0.4 lru-dict==1.3.0 PyJWT==2.8.0 packaging==26.4
  aiohttp-fast-url-dispatcher==0.3.0 aiohttp-zlib-ng==0.3.1 zlib-ng==1.1.0 cryptography==42.0.5
  cffi==2.1.1 ifaddr==0.2.0 certifi==2026.10.19.post1)
ha_check='import homeassistant.components.modbus, homeassistant.const as c; assert c.__version__ == "2024.3.3"'
if [ ! -x "$ha_venv/bin/python" ] || [ ! -x "$ha_venv/bin/pip" ]; then
  echo "== $python -m venv $ha_venv"
  "$python" -m venv --clear "$ha_venv"
fi
if ! "$ha_venv/bin/python" -c "$ha_check" >/dev/null 2>&1; then
  echo "== $ha_venv/bin/pip install --no-deps homeassistant==2024.3.3 and what its modbus schema imports"
  "$ha_venv/bin/pip" install --quiet --disable-pip-version-check --no-deps "${ha_pins[@]}"
fi
echo "Home Assistant: $("$ha_venv/bin/python" -c 'import homeassistant.const as c; print(c.__version__)' 2>/dev/null || echo MISSING) (modbus schema)"
