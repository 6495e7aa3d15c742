#!/usr/bin/env bash
# Installs the third-party Modbus peers the interop tests (tests/tests/interop_*.rs) talk to.
# Idempotent: installs only what is missing.
#
# - Debian packages mbpoll and socat, with apt-get when running as root (otherwise prints the
#   command to run);
# - for the bridge tests (cli/tests/bridge.rs) prometheus, mosquitto, mosquitto-clients and
#   openssl, without their recommendations (prometheus recommends node-exporter and more);
# - Node-RED and node-red-contrib-modbus from npm under target/interop-node (the Node-RED export's
#   test, cli/tests/export_node_red.rs), pinned: node-red-contrib-modbus 5.23.3 is the newest the
#   registry serves that runs on Debian's Node.js 20 (5.60 needs Node 22) and installs from npm
#   alone (5.45 fetches a dependency from another host); ~25 s on an empty npm cache;
# - Python packages pymodbus, minimalmodbus and pyserial in a venv at target/interop-venv, at the
#   versions the scripts in tests/interop/ are written for (pymodbus changes its API between
#   minor versions), and jsonschema, which cli/tests/machine_output.rs checks the CLI's JSON
#   output with (docs/schema/).
set -euo pipefail
cd "$(dirname "$0")/../.."

missing=()
for tool in mbpoll socat npm; do
  command -v "$tool" >/dev/null 2>&1 || missing+=("$tool")
done
bare=()
for pair in prometheus:prometheus mosquitto:mosquitto mosquitto_sub:mosquitto-clients openssl:openssl; do
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
if [ ! -x "$venv/bin/python" ]; then
  echo "== $python -m venv $venv"
  "$python" -m venv "$venv"
fi
pins=(pymodbus==3.16.1 minimalmodbus==2.1.1 pyserial==3.5 jsonschema==4.26.0)
check='import pymodbus, minimalmodbus, serial, importlib.metadata
assert (pymodbus.__version__, minimalmodbus.__version__, serial.__version__) == ("3.16.1", "2.1.1", "3.5")
assert importlib.metadata.version("jsonschema") == "4.26.0"'
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
