// Talking to the server: JSON requests with the run's token, and the spheres' PNGs.

import { state } from "./state.js";

const headers = () => ({ Authorization: `token ${state.token}` });

// An error with the server's one line (and its status).
function failure(status, data, fallback) {
  const err = new Error((data && data.error) || fallback);
  err.status = status;
  return err;
}

// `method url` with a JSON body; its JSON answer, or an Error with the server's message.
export async function api(method, url, body) {
  const r = await fetch(url, {
    method,
    headers: { "Content-Type": "application/json", ...headers() },
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  const data = await r.json().catch(() => null);
  if (!r.ok) throw failure(r.status, data, r.statusText);
  return data;
}

// A sphere's PNG of the API: {blob, passes (the passes in it, its X-Passes)}.
export async function png(url) {
  const r = await fetch(url, { headers: headers() });
  if (!r.ok) throw failure(r.status, await r.json().catch(() => null), r.statusText);
  return { blob: await r.blob(), passes: +r.headers.get("X-Passes") };
}
