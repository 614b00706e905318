/* http_conn.c — the HTTP server's connections (see http_int.h): their deadlines and the reaper
 * that enforces them, the check of a connection's first byte, the URL unescaper, and the count
 * of parked (suspended, not yet answered) connections that http_stop waits for.
 *
 * Deadlines: MHD's own timeout is for idleness only, so a client that sends its headers a
 * byte at a time, each in time, holds a connection for ever.  Each connection here has a
 * deadline for what it is reading: its headers (--header-timeout, from the connection's start
 * or the end of its previous request plus the idle timeout), then its body
 * (--body-timeout).  While its request is handled or answered it has none (a wait is bounded
 * by --max-wait, an answer by MHD's idle timeout).  The reaper thread shuts down the socket
 * of a connection past its deadline; MHD then sees it closed and cleans it up.  MHD calls the
 * CLOSED notification, which unlinks the context under h->conns_mu, before it closes the
 * socket, so the reaper never shuts a socket number that has been reused.
 *
 * Threads: the notifications and the unescaper run on MHD's threads, the reaper on its own;
 * h->conns and every deadline are guarded by h->conns_mu.
 */
#include "server/http_int.h"

#include <ctype.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>

#include "server/log.h"

/* c is suspended and not yet answered (h->parked counts those: http_stop waits for them). */
void http_park(conn *c)
{
    if (!c->parked) {
        c->parked = 1;
        atomic_fetch_add(&c->h->parked, 1);
    }
}

void http_unpark(conn *c)
{
    if (c->parked) {
        c->parked = 0;
        atomic_fetch_sub(&c->h->parked, 1);
    }
}

/* mc's socket context, or NULL (none could be made for it) */
sock_ctx *http_sock_of(struct MHD_Connection *mc)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(mc, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    return ci ? ci->socket_context : NULL;
}

/* Sets the deadline of mc's connection: `secs` from now for `reading`, or none (secs 0). */
void http_set_deadline(http_server *h, struct MHD_Connection *mc, double secs, const char *reading)
{
    sock_ctx *sc = http_sock_of(mc);
    if (!sc) return;
    pthread_mutex_lock(&h->conns_mu);
    sc->deadline = secs > 0 ? engine_now() + secs : 0;
    sc->reading = reading;
    pthread_mutex_unlock(&h->conns_mu);
}

/* Can a request begin with byte c?  A request line begins with its method, a token (letters,
 * digits and !#$%&'*+-.^_`|~), and may follow a few empty lines (CR, LF). */
static int request_first_byte(unsigned char c)
{
    return isalnum(c) || (c && strchr("!#$%&'*+-.^_`|~\r\n", c));
}

/* MHD (0.9.75) takes a line whose first byte is NUL for an empty line before the request line,
 * skips it and waits for a request line until the header deadline (10 s).  A connection whose
 * first byte can begin no request is answered 400 here, as MHD accepts it, and shut at once;
 * MHD then finds it closed.  The listening socket defers each accept until the connection's
 * first bytes are in (TCP_DEFER_ACCEPT, up to the header timeout), so they are there to see. */
static void refuse_bad_start(int fd)
{
    unsigned char b;
    if (recv(fd, &b, 1, MSG_PEEK | MSG_DONTWAIT) != 1 || request_first_byte(b)) return;
    static const char body[] =
        "{\"type\":\"about:blank\",\"title\":\"Bad Request\",\"status\":400,\"detail\":"
        "\"the request begins with a byte no request line can hold\"}";
    char msg[512];
    int n = snprintf(msg, sizeof msg,
                     "HTTP/1.1 400 Bad Request\r\nConnection: close\r\n"
                     "Content-Type: application/problem+json\r\nContent-Length: %zu\r\n\r\n%s",
                     sizeof body - 1, body);
    if (n > 0 && (size_t)n < sizeof msg)
        (void)send(fd, msg, (size_t)n, MSG_NOSIGNAL | MSG_DONTWAIT);
    shutdown(fd, SHUT_RDWR);
    log_kv(LOG_INFO, "request refused: a first byte no request line can begin with", NULL);
}

/* MHD_OPTION_NOTIFY_CONNECTION: a sock_ctx for each TCP connection. */
void http_notify_connection(void *cls, struct MHD_Connection *mc, void **socket_context,
                            enum MHD_ConnectionNotificationCode toe)
{
    http_server *h = cls;
    if (toe == MHD_CONNECTION_NOTIFY_STARTED) {
        const union MHD_ConnectionInfo *fi =
            MHD_get_connection_info(mc, MHD_CONNECTION_INFO_CONNECTION_FD);
        if (fi) refuse_bad_start(fi->connect_fd);
        /* NULL (out of memory): no escape check and no deadline for this one */
        sock_ctx *sc = calloc(1, sizeof *sc);
        const union MHD_ConnectionInfo *ci =
            MHD_get_connection_info(mc, MHD_CONNECTION_INFO_CONNECTION_FD);
        if (sc && ci) {
            sc->fd = ci->connect_fd;
            sc->reading = "headers";
            pthread_mutex_lock(&h->conns_mu);
            sc->deadline = engine_now() + h->cfg->header_timeout;
            sc->next = h->conns;
            if (h->conns) h->conns->prev = sc;
            h->conns = sc;
            pthread_mutex_unlock(&h->conns_mu);
        }
        *socket_context = sc && ci ? sc : NULL;
        if (sc && !ci) free(sc);
    } else if (toe == MHD_CONNECTION_NOTIFY_CLOSED) {
        sock_ctx *sc = *socket_context;
        if (sc) {
            pthread_mutex_lock(&h->conns_mu);
            if (sc->prev)
                sc->prev->next = sc->next;
            else
                h->conns = sc->next;
            if (sc->next) sc->next->prev = sc->prev;
            pthread_mutex_unlock(&h->conns_mu);
            free(sc);
        }
        *socket_context = NULL;
    }
}

/* Shuts the sockets of connections past their deadline, four times a second. */
static void *reaper_main(void *arg)
{
    http_server *h = arg;
    pthread_mutex_lock(&h->conns_mu);
    while (!h->reaper_stop) {
        double now = engine_now(), t = now + 0.25;
        struct timespec ts = {.tv_sec = (time_t)t,
                              .tv_nsec = (long)((t - (double)(time_t)t) * 1e9)};
        pthread_cond_timedwait(&h->reaper_cv, &h->conns_mu, &ts);
        now = engine_now();
        for (sock_ctx *sc = h->conns; sc; sc = sc->next)
            if (sc->deadline > 0 && now > sc->deadline) {
                sc->deadline = 0;
                shutdown(sc->fd, SHUT_RDWR);
                log_kv(LOG_INFO, "connection closed: too slow", "reading", sc->reading, NULL);
            }
    }
    pthread_mutex_unlock(&h->conns_mu);
    return NULL;
}

static int hexval(char ch)
{
    return ch >= '0' && ch <= '9'   ? ch - '0'
           : ch >= 'a' && ch <= 'f' ? ch - 'a' + 10
           : ch >= 'A' && ch <= 'F' ? ch - 'A' + 10
                                    : -1;
}

/* MHD_OPTION_UNESCAPE_CALLBACK: decodes %XX in place (the path and the query's keys and
 * values), as MHD's own does, but notes what MHD lets through: %00, which would cut the
 * string short (/healthz%00x was /healthz), and a % without two hex digits.  The handler
 * then answers 400. */
size_t http_unescape(void *cls, struct MHD_Connection *mc, char *s)
{
    (void)cls;
    char *w = s;
    int bad = 0;
    for (const char *r = s; *r;) {
        int hi, lo;
        if (*r != '%') {
            *w++ = *r++;
        } else if ((hi = hexval(r[1])) >= 0 && (lo = hexval(r[2])) >= 0 && (hi || lo)) {
            *w++ = (char)(hi * 16 + lo);
            r += 3;
        } else {
            bad = 1;
            *w++ = *r++; /* left as it is */
        }
    }
    *w = 0;
    sock_ctx *sc = bad ? http_sock_of(mc) : NULL;
    if (sc) sc->bad_escape = 1;
    return (size_t)(w - s);
}

/* Starts the reaper thread: 0, or -1 when it cannot be started. */
int http_reaper_start(http_server *h)
{
    if (pthread_create(&h->reaper, NULL, reaper_main, h) != 0) return -1;
    h->reaper_started = 1;
    return 0;
}

/* Stops the reaper thread (when it was started). */
void http_reaper_stop(http_server *h)
{
    if (!h->reaper_started) return;
    pthread_mutex_lock(&h->conns_mu);
    h->reaper_stop = 1;
    pthread_cond_signal(&h->reaper_cv);
    pthread_mutex_unlock(&h->conns_mu);
    pthread_join(h->reaper, NULL);
    h->reaper_started = 0;
}
