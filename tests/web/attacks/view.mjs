// What the attacks do with a tab (gateway_client.mjs's connect()): open a
// view and wait for its first frame, keep it busy with camera events, and
// time the frames that arrive.
export const kPhantom = 'phantom:abdomen?size=48';
const kSize = { width: 64, height: 64 };

// Opens kPhantom in `tab`; resolves with the 'opened' message once the
// first frame is in. Rejects with the gateway's error message.
export async function openView(tab, { timeoutMs = 60000 } = {}) {
  tab.send({ type: 'open', source: kPhantom, settings: kSize });
  const first = await tab.next((m) => m.type === 'opened' || m.type === 'error', timeoutMs);
  if (first.type === 'error') throw new Error(`open refused: ${first.code}: ${first.message}`);
  await tab.next((m) => m.type === 'frame', timeoutMs);
  return first;
}

// Arrival times (performance.now(), ms) of every frame `tab` gets from now on.
export function frameClock(tab) {
  const times = [];
  tab.ws.on('message', (data, isBinary) => {
    if (isBinary) times.push(performance.now());
  });
  return times;
}

// Orbits `tab`'s camera by a degree every `everyMs` for `ms`: each event
// asks the server for a frame.
export async function orbit(tab, ms, { everyMs = 40, from = 0 } = {}) {
  const end = performance.now() + ms;
  let sequence = from;
  while (performance.now() < end) {
    sequence += 1;
    tab.send({ type: 'event', event: { sequence, camera: { azimuth_deg: sequence % 360,
                                                          elevation_deg: 10 } } });
    await new Promise((r) => setTimeout(r, everyMs));
  }
  return sequence;
}

// Frames in [t0, t1) and the longest gap between frames (or the window's
// ends) in it, ms.
export function framesIn(times, t0, t1) {
  const inside = times.filter((t) => t >= t0 && t < t1);
  let gap = 0;
  let last = t0;
  for (const t of [...inside, t1]) {
    gap = Math.max(gap, t - last);
    last = t;
  }
  return { frames: inside.length, fps: inside.length / ((t1 - t0) / 1000), longestGapMs: gap };
}

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

export async function closeTab(tab) {
  tab.ws.close();
  await tab.closed;
}
