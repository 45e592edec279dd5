#!/usr/bin/env bash
# Loadtests of two servers on one PostgreSQL behind nginx (round robin, deploy/nginx.conf), and
# of one server on SQLite, on this machine, in one run: `dualrep loadtest --addr` at 200 / 20 and
# 2,000 / 200 trainer sockets / sessions against each. Also the CPU seconds each process used
# during each loadtest (from /proc/PID/stat), for the per-session cost.
#
#   bash docs/results/loadtest-postgres/run.sh BINARY OUT_DIR [SECONDS]
#
# LOADS (environment): the trainer/session pairs, default "200/20 1000/100 2000/200".
# BINARY: a release `dualrep` (a copy outside target/). Needs Debian's postgresql and nginx; as
# root, PostgreSQL runs as the user dualrep-pg (created by the tests' support, or here).
set -euo pipefail
bin=$(readlink -f "$1"); out=$(readlink -f "$2"); seconds=${3:-20}
loads=${LOADS:-"200/20 1000/100 2000/200"}
repo=$(cd "$(dirname "$0")/../../.." && pwd)
mkdir -p "$out"
work=$(mktemp -d); chmod 755 "$work"
pgbin=$(ls -d /usr/lib/postgresql/*/bin | sort -V | tail -1)
pids=()
nginx_master=""
cleanup() {
  # nginx's workers outlive a killed master: ask the master to stop them first.
  [ -z "$nginx_master" ] || { kill -QUIT "$nginx_master" 2>/dev/null || true; sleep 1; pkill -9 -P "$nginx_master" 2>/dev/null || true; }
  for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT
free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
as_pg() { if [ "$(id -u)" = 0 ]; then runuser -u dualrep-pg -- "$@"; else "$@"; fi; }
# CPU seconds (user + system) of a process and its threads so far.
# (0 for one that has gone: a PostgreSQL backend may end between the listing and the reading.)
cpu() { awk -v t="$(getconf CLK_TCK)" '{print ($14 + $15) / t}' "/proc/$1/stat" 2>/dev/null || echo 0; }
# The sum over every process whose command line matches.
cpu_of() { local s=0 c; for p in $(pgrep -f "$1"); do c=$(cpu "$p"); s=$(python3 -c "print($s + ${c:-0})"); done; echo "$s"; }

# PostgreSQL 15 from Debian, trust on loopback, enough connections for two servers' pools.
id dualrep-pg >/dev/null 2>&1 || { [ "$(id -u)" != 0 ] || useradd --system --user-group --no-create-home dualrep-pg; }
mkdir -p "$work/pg"; [ "$(id -u)" != 0 ] || chown dualrep-pg:dualrep-pg "$work/pg"
as_pg "$pgbin/initdb" -D "$work/pg/data" -U postgres -A trust >/dev/null
pgport=$(free_port)
as_pg "$pgbin/postgres" -D "$work/pg/data" -p "$pgport" -k "$work/pg" -c listen_addresses=127.0.0.1 \
  -c max_connections=200 > "$work/pg.log" 2>&1 &
pids+=($!)
for i in $(seq 100); do as_pg "$pgbin/pg_isready" -q -h 127.0.0.1 -p "$pgport" && break; sleep 0.1; done
as_pg "$pgbin/createdb" -h 127.0.0.1 -p "$pgport" -U postgres dualrep
url="postgres://postgres@127.0.0.1:$pgport/dualrep"

serve() { # NAME PORT ARGS...: a server, its pid in $server_pid
  local name=$1 port=$2; shift 2
  mkdir -p "$work/$name"
  "$bin" serve --addr 127.0.0.1:$port --data-dir "$work/$name" --token lt --max-sessions 200 "$@" \
    > "$work/$name.log" 2>&1 &
  server_pid=$!; pids+=($server_pid)
  for i in $(seq 100); do curl -sf 127.0.0.1:$port/healthz >/dev/null && return; sleep 0.1; done
  echo "server $name did not start" >&2; cat "$work/$name.log" >&2; exit 1
}

loadtest() { # LABEL ADDR TRAINERS SESSIONS PIDS...: one loadtest and the CPU each process used
  local label=$1 addr=$2 trainers=$3 sessions=$4; shift 4
  local before=() p i
  for p in "$@"; do before+=("$(cpu $p)"); done
  local pg_before; pg_before=$(cpu_of "postgres.*$work/pg|postgres: ")
  local t0; t0=$(date +%s.%N)
  # The client's own CPU seconds (it shares the machine) go to client.cpu.
  python3 -c 'import resource, subprocess, sys
r = subprocess.run(sys.argv[2:], stdout=open(sys.argv[1], "w")).returncode
u = resource.getrusage(resource.RUSAGE_CHILDREN)
print(round(u.ru_utime + u.ru_stime, 2), file=open(sys.argv[1] + ".cpu", "w")); sys.exit(r)' \
    "$work/report.json" "$bin" loadtest --addr "$addr" --token lt --trainers "$trainers" \
    --sessions "$sessions" --seconds "$seconds"
  local wall; wall=$(python3 -c "import time; print(time.time() - $t0)")
  local cpus="{" sep=""
  i=0; for p in "$@"; do cpus+="$sep\"$p\": $(python3 -c "print(round($(cpu $p) - ${before[$i]}, 2))")"; sep=", "; i=$((i+1)); done
  cpus+="$sep\"postgres\": $(python3 -c "print(round($(cpu_of "postgres.*$work/pg|postgres: ") - $pg_before, 2))")"
  cpus+=", \"loadtest client\": $(cat "$work/report.json.cpu")}"
  python3 - "$label" "$wall" "$cpus" "$work/report.json" >> "$out/runs.jsonl" <<'PY'
import json, sys, platform
label, wall, cpus, path = sys.argv[1], float(sys.argv[2]), json.loads(sys.argv[3]), sys.argv[4]
r = json.load(open(path))
print(json.dumps({"setup": label, "wall_s": round(wall, 2), "cpu_s": cpus, "report": r}))
PY
  tail -1 "$out/runs.jsonl"
}

# Two servers on PostgreSQL behind nginx.
pa=$(free_port); serve a "$pa" --database "$url"; a_pid=$server_pid
pb=$(free_port); serve b "$pb" --database "$url"; b_pid=$server_pid
proxy=$(free_port)
mkdir -p "$work/nginx"
python3 - "$repo/deploy/nginx.conf" "$work/nginx" "$proxy" "$pa" "$pb" > "$work/nginx/nginx.conf" <<'PY'
import re, sys, os
conf, d, port, a, b = sys.argv[1:]
s = open(conf).read()
s = re.sub(r"upstream dualrep \{[^}]*\}", f"upstream dualrep {{\n        server 127.0.0.1:{a} max_fails=1 fail_timeout=2s;\n        server 127.0.0.1:{b} max_fails=1 fail_timeout=2s;\n    }}", s)
s = s.replace("listen 8080;", f"listen 127.0.0.1:{port};")
s = s.replace("    access_log off;", "    access_log off;\n" + "".join(f"    {k}_temp_path {d}/{k};\n" for k in ["client_body", "proxy", "fastcgi", "uwsgi", "scgi"]))
user = "user nobody nogroup;\n" if os.getuid() == 0 else ""
print(f"{user}pid {d}/nginx.pid;\nerror_log {d}/error.log warn;\n" + s)
PY
/usr/sbin/nginx -e stderr -p "$work/nginx" -c "$work/nginx/nginx.conf" -g 'daemon off;' 2> "$work/nginx.log" &
nginx_master=$!
for i in $(seq 100); do curl -s -o /dev/null 127.0.0.1:$proxy/healthz && break; sleep 0.1; done
nginx_workers=$(pgrep -P "$nginx_master" | tr '\n' ' ')
for load in $loads; do
  loadtest "postgres-2-servers-nginx" "127.0.0.1:$proxy" ${load%/*} ${load#*/} $a_pid $b_pid $nginx_workers
done
kill -TERM $a_pid $b_pid; wait $a_pid $b_pid 2>/dev/null || true

# One server on SQLite (the README's main command), on the same machine.
ps_=$(free_port); serve sqlite "$ps_"; s_pid=$server_pid
for load in $loads; do
  loadtest "sqlite-1-server" "127.0.0.1:$ps_" ${load%/*} ${load#*/} $s_pid
done
kill -TERM $s_pid; wait $s_pid 2>/dev/null || true
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(grep -o -m1 -w 'avx512f' /proc/cpuinfo || echo 'no avx512'); binary $(basename "$bin")" >> "$out/machine.txt"
