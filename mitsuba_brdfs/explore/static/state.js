// The page's state, all of it: every other module reads and changes this object, and
// keeps nothing of its own but constants.

export const state = {
  // the run's token, from the address explore printed (...?token=...): sent with every
  // request to the API, which refuses requests without it
  token: new URLSearchParams(location.search).get("token") || "",

  // what the server said at start
  variant: "",
  passes: 8,            // passes of a sphere
  passSpp: 4,           // samples per pixel of a pass
  maxEntries: 16,

  // the BSDFs, as the server last described them: {id, label, plugin, colour, visible,
  // version, exportable, controls: [{name, kind, value, set, active, partners,
  // alternatives, ...}]}
  entries: [],
  // id -> the latest data of every plot of the entry ({polar, lobe, ...} or {error})
  data: new Map(),
  // the incidence the polar plot's data are for
  thetaI: null,

  // the plots' requests: one in flight at a time (busy); what the next one asks for
  busy: false,
  want: { parts: new Set(), ids: new Set(), all: false },
  // parameter changes waiting to go with a plots request: {entry, name, value, done, fail}
  sets: [],
  // sliders: "id/name" -> {value, again} while a change of it is under way
  sliding: new Map(),

  // the spheres: a new run (a change, a new light) stops the passes of the previous one
  sphereRun: 0,
  sphereFetch: null,

  // the check running ({id, label, mine: started by this page}), or null: one at a time
  check: null,

  // fitting a model to a measured entry: the fit running ({id, label, model, mine}) or
  // null (one at a time), the models offered, the budget of a fit ({samples, evaluations
  // a stage, most: of every stage together})
  fit: null,
  fitModels: [],
  fitBudget: { samples: 0, evaluations: 0, most: 0 },
};
