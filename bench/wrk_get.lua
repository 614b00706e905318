-- wrk script: GET a cached result; prints p50/p99.
function done(summary, latency, requests)
  io.write(string.format("non-2xx/3xx responses: %d (of %d)\n", summary.errors.status, summary.requests))
  io.write(string.format("p50 %.2f ms  p99 %.2f ms\n", latency:percentile(50) / 1000,
                         latency:percentile(99) / 1000))
end
