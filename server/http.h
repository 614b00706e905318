/* http.h — the HTTP API of DESIGN.md ("The service") on libmicrohttpd: routing, request bodies
 * with a size limit, Prefer: wait on suspended connections (resumed by the engine's wake
 * callback, from a worker or the timer thread), ETag/304, problem+json errors, metrics, the
 * OpenAPI document and a small page at /.  Every request gets exactly one response, and one
 * log line when it completes.
 *
 * libmicrohttpd runs its own threads (internal polling thread, epoll, a small pool); the
 * handlers only parse, look up and queue: jobs run on the engine's workers.
 */
#ifndef CELLAR_HTTP_H
#define CELLAR_HTTP_H

#include "server/config.h"
#include "server/engine.h"
#include "server/metrics.h"
#include "server/store.h"

typedef struct http_server http_server;

/* Starts listening on cfg->host:cfg->port (all borrowed, must outlive the server).
 * Returns NULL with a message in err on failure. */
http_server *http_start(const config *cfg, engine *e, store *st, metrics *m, char *err,
                        size_t errlen);
/* The port actually bound (useful with port 0). */
unsigned http_port(http_server *h);
/* /readyz answers 503 and POST /v1/jobs 503 from now on. */
void http_set_draining(http_server *h);
/* Stops the daemon (every suspended connection must have been woken: engine_drain). */
void http_stop(http_server *h);

#endif
