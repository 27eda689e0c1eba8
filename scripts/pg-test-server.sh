#!/usr/bin/env bash
# A throwaway PostgreSQL server for the tests (Debian's postgresql package):
# a cluster in DIR/data, run by an unprivileged user (the caller, or
# `nobody` when the caller is root, as PostgreSQL refuses root), listening
# only on a Unix socket in DIR/socket (no TCP port), trust authentication
# for that socket alone. `start` writes the libpq connection string to
# DIR/conninfo; `stop` stops it and removes DIR.
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
case "$action" in
  start)
    if [ -f "$dir/data/postmaster.pid" ]; then "$0" stop "$dir" || true; fi
    rm -rf "$dir"
    mkdir -p "$dir/data" "$dir/socket"
    [ "$(id -u)" -eq 0 ] && chown -R nobody "$dir"
    "${as_user[@]}" "$bin/initdb" -D "$dir/data" --auth=trust --username="$user" \
      --encoding=UTF8 --locale=C.UTF-8 > "$dir/initdb.log" 2>&1 ||
      { cat "$dir/initdb.log" >&2; exit 1; }
    "${as_user[@]}" "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 60 \
      -o "-c listen_addresses='' -k $dir/socket" start > /dev/null ||
      { cat "$dir/server.log" >&2; exit 1; }
    echo "host=$dir/socket dbname=postgres user=$user" > "$dir/conninfo"
    echo "pg-test-server: PostgreSQL on $dir/socket (user $user)"
    ;;
  stop)
    if [ -d "$dir/data" ]; then
      "${as_user[@]}" "$bin/pg_ctl" -D "$dir/data" -m immediate -w stop > /dev/null 2>&1 || true
    fi
    rm -rf "$dir"
    ;;
  *) echo "usage: pg-test-server.sh start|stop DIR" >&2; exit 2 ;;
esac
