#!/usr/bin/env bash
# One loadtest of a server binary: start it, run the current loadtest client against it, stop it.
set -u
server=$1; client=$2; port=$3
dir=$(mktemp -d)
$server serve --addr 127.0.0.1:$port --data-dir $dir --token lt --max-sessions 50 > $dir/serve.log 2>&1 &
pid=$!
for i in $(seq 50); do curl -sf localhost:$port/healthz >/dev/null && break; sleep 0.2; done
$client loadtest --addr 127.0.0.1:$port --token lt --trainers 500 --sessions 50 --seconds 20
kill -TERM $pid; wait $pid 2>/dev/null
rm -rf $dir
