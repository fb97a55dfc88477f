// The services' heartbeats (concert/system/status, every 200 ms from each service): which
// services run, and how fresh each one's last heartbeat is.
import { now } from './ui.js';

/// service@host -> {status, seen, beat, epoch}: `seen` when any sample arrived, `beat` when the
/// last *new* heartbeat arrived (both now() [ms]).
export const services = new Map();

/// Keeps `services` up to date from `link`.
export function trackServices(link) {
  link.subscribe('concert/system/status', (s) => {
    const key = s.service + '@' + s.host;
    const before = services.get(key);
    // The first sample after a (re)subscription is the gateway's cached copy, maybe minutes
    // old: it says what the service reported last, not that it is alive. A heartbeat counts
    // only when it is newer than the one before it on this subscription.
    const replay = !before || before.epoch !== link.subEpoch;
    const newer = !replay && s.stamp_ns > before.status.stamp_ns;
    services.set(key, {
      status: s, seen: now(), epoch: link.subEpoch,
      beat: newer ? now() : before ? before.beat : -Infinity,
    });
  });
}

/// The status of a running `name` (heard within `maxMs`, not stopped), else null.
export function alive(name, maxMs = 3000) {
  const t = now();
  for (const s of services.values()) {
    if (s.status.service === name && t - s.seen < maxMs && s.status.state !== 'SERVICE_STOPPED') return s.status;
  }
  return null;
}

/// Milliseconds since `name`'s newest live heartbeat (Infinity: none, or it reported STOPPED).
export function beatAge(name) {
  let best = Infinity;
  for (const s of services.values()) {
    if (s.status.service === name && s.status.state !== 'SERVICE_STOPPED') best = Math.min(best, now() - s.beat);
  }
  return best;
}

/// The newest status of `name` (any host), or null.
export function statusOf(name) {
  let best = null;
  for (const s of services.values()) {
    if (s.status.service === name && (!best || s.status.stamp_ns > best.stamp_ns)) best = s.status;
  }
  return best;
}
