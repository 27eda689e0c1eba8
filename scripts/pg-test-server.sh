#!/usr/bin/env bash
# A throwaway PostgreSQL server for the tests (Debian's postgresql package):
# a cluster run by an unprivileged user (the caller, or `nobody` when the
# caller is root, as PostgreSQL refuses root), listening only on a Unix
# socket (no TCP port), trust authentication for that socket alone. The
# cluster and its socket live in a fresh folder under /tmp (short enough for
# a socket path, and reachable by `nobody` wherever DIR is); DIR keeps the
# libpq connection string (DIR/conninfo) and where the cluster is
# (DIR/cluster). `stop` stops it and removes both.
#
# Usage: pg-test-server.sh start|stop DIR
set -euo pipefail
action="${1:?usage: pg-test-server.sh start|stop DIR}"
dir="${2:?usage: pg-test-server.sh start|stop DIR}"
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1)
[ -x "$bin/initdb" ] || { echo "pg-test-server: PostgreSQL is not installed (apt install postgresql)" >&2; exit 1; }
as_user=()
user=$(id -un)
if [ "$(id -u)" -eq 0 ]; then
  user=nobody
  as_user=(runuser -u nobody --)
fi
stop() {
  [ -f "$dir/cluster" ] || return 0
  local cluster
  cluster=$(cat "$dir/cluster")
  if [ -d "$cluster/data" ]; then
    "${as_user[@]}" "$bin/pg_ctl" -D "$cluster/data" -m immediate -w stop > /dev/null 2>&1 || true
  fi
  case "$cluster" in /tmp/vpm-pg.*) rm -rf "$cluster" ;; esac
}
case "$action" in
  start)
    stop
    rm -rf "$dir"
    mkdir -p "$dir"
    cluster=$(mktemp -d /tmp/vpm-pg.XXXXXX)
    echo "$cluster" > "$dir/cluster"
    mkdir -p "$cluster/data" "$cluster/socket"
    [ "$(id -u)" -eq 0 ] && chown -R nobody "$cluster"
    "${as_user[@]}" "$bin/initdb" -D "$cluster/data" --auth=trust --username="$user" \
      --encoding=UTF8 --locale=C.UTF-8 > "$dir/initdb.log" 2>&1 ||
      { cat "$dir/initdb.log" >&2; exit 1; }
    "${as_user[@]}" "$bin/pg_ctl" -D "$cluster/data" -l "$cluster/server.log" -w -t 60 \
      -o "-c listen_addresses='' -k $cluster/socket" start > /dev/null ||
      { cat "$cluster/server.log" >&2; exit 1; }
    echo "host=$cluster/socket dbname=postgres user=$user" > "$dir/conninfo"
    echo "pg-test-server: PostgreSQL on $cluster/socket (user $user)"
    ;;
  stop)
    stop
    rm -rf "$dir"
    ;;
  *) echo "usage: pg-test-server.sh start|stop DIR" >&2; exit 2 ;;
esac
