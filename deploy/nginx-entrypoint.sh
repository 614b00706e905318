#!/bin/sh
# The upstream of deploy/nginx.conf from CELLAR_UPSTREAMS ("host:port host:port ..."), then
# nginx in the foreground.
set -eu
site=/etc/nginx/sites-available/cellar
if [ -n "${CELLAR_UPSTREAMS:-}" ]; then
    servers=""
    for u in $CELLAR_UPSTREAMS; do
        servers="$servers    server $u max_fails=1 fail_timeout=5s;\n"
    done
    awk -v s="$servers" '
        /^upstream cellard \{/ { print; printf "%s", s; skip = 1; next }
        skip && /^ *server / { next }
        { skip = skip && !/^\}/; print }' "$site" > "$site.new"
    mv "$site.new" "$site"
fi
[ -e /proc/net/if_inet6 ] || sed -i '/listen \[::\]/d' "$site" # no IPv6 in this container
nginx -t -q
exec nginx -g 'daemon off;'
