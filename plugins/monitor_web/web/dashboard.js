// The PLR dashboard: renders the monitor's state document (pushed over the
// WebSocket at /ws, up to update_hz times a second) as SVG and tables.
// Plain browser JavaScript, no libraries, nothing fetched from elsewhere.
'use strict';

const SVG = 'http://www.w3.org/2000/svg';

function el(tag, attrs, parent) {
  const e = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

function fmt(x, digits) {
  return typeof x === 'number' ? x.toFixed(digits) : '–';
}

// One projection of the world: `u` and `v` pick the axes (0 x, 1 y, 2 z);
// v grows upwards on screen.
function drawView(svg, world, u, v) {
  svg.replaceChildren();
  const t = world.trailer;
  if (!t) return;
  // trailer_size is (width, height, depth); x runs from the rear (0) to the front (depth).
  const extent = [[0, t[2]], [-t[0] / 2, t[0] / 2], [0, t[1]]];
  let lo = extent[u][0], hi = extent[u][1];
  for (const r of world.robot || []) lo = Math.min(lo, r.c[u] - r.h[u]);
  const W = 1000, H = 220, pad = 10;
  const vlo = extent[v][0], vhi = extent[v][1];
  const s = Math.min((W - 2 * pad) / (hi - lo), (H - 2 * pad) / (vhi - vlo + 0.4));
  const X = (a) => pad + (a - lo) * s;
  const Y = (b) => H - pad - (b - vlo) * s;
  el('rect', {class: 'trailer', x: X(extent[u][0]), y: Y(extent[v][1]),
              width: (extent[u][1] - extent[u][0]) * s, height: (vhi - vlo) * s}, svg);
  const rect = (b, cls) => {
    const r = el('rect', {class: cls, x: X(b.c[u] - b.h[u]), y: Y(b.c[v] + b.h[v]),
                          width: 2 * b.h[u] * s, height: 2 * b.h[v] * s}, svg);
    if (b.id !== undefined) r.setAttribute('data-id', b.id);
  };
  // Drawn far to near, so the nearer boxes cover the ones behind.
  const depthAxis = 3 - u - v;
  const order = [...(world.boxes || [])].sort((a, b) =>
      depthAxis === 2 ? a.c[2] - b.c[2] : b.c[depthAxis] - a.c[depthAxis]);
  for (const b of order) rect(b, 'box');
  for (const r of world.robot || []) rect(r, 'robot');
}

function drawCurve(svg, curve, total) {
  svg.replaceChildren();
  const W = 500, H = 200, L = 40, B = 24;
  const tmax = Math.max(10, ...curve.map((p) => p[0]));
  const nmax = Math.max(1, total || 0, ...curve.map((p) => p[1]));
  const X = (t) => L + (t / tmax) * (W - L - 10);
  const Y = (n) => H - B - (n / nmax) * (H - B - 10);
  el('line', {class: 'axis', x1: L, y1: H - B, x2: W - 10, y2: H - B}, svg);
  el('line', {class: 'axis', x1: L, y1: H - B, x2: L, y2: 10}, svg);
  el('text', {class: 'label', x: W - 10, y: H - 8, 'text-anchor': 'end'}, svg).textContent =
      `robot time ${fmt(tmax, 0)} s`;
  el('text', {class: 'label', x: 4, y: 14}, svg).textContent = `${nmax} boxes`;
  // A step per box: the count holds until the next box leaves.
  const points = [[0, 0]];
  for (const [t, n] of curve) points.push([t, points[points.length - 1][1]], [t, n]);
  el('polyline', {class: 'curve', id: 'curve-line', 'data-points': curve.length,
                  'data-boxes': curve.length ? curve[curve.length - 1][1] : 0,
                  points: points.map((p) => `${X(p[0])},${Y(p[1])}`).join(' ')}, svg);
}

// The strategy tree as nested lists; the node being executed is marked.
function drawStrategy(div, strategy, active) {
  div.replaceChildren();
  document.getElementById('strategy-name').textContent = strategy ? `'${strategy.name}'` : '';
  if (!strategy || !strategy.nodes.length) return;
  const seen = new Set();
  const item = (index, edge) => {
    const li = document.createElement('li');
    const node = strategy.nodes[index];
    if (index === active) li.className = 'active';
    if (edge) {
      const e = document.createElement('span');
      e.className = 'edge';
      e.textContent = `${edge} → `;
      li.appendChild(e);
    }
    const label = document.createElement('span');
    label.textContent = node ? node.action : '?';
    label.dataset.node = index;
    li.appendChild(label);
    if (node && !seen.has(index)) {
      seen.add(index);
      if (node.children.length) {
        const ul = document.createElement('ul');
        for (const c of node.children) ul.appendChild(item(c.child, c.observation));
        li.appendChild(ul);
      }
    }
    return li;
  };
  const ul = document.createElement('ul');
  ul.appendChild(item(strategy.root, null));
  div.appendChild(ul);
}

function fillTable(id, rows) {
  const body = document.querySelector(`#${id} tbody`);
  body.replaceChildren();
  for (const row of rows) {
    const tr = document.createElement('tr');
    for (const cell of row) {
      const td = document.createElement('td');
      if (typeof cell === 'object' && cell !== null) {
        td.textContent = cell.text;
        if (cell.cls) td.className = cell.cls;
        for (const [k, v] of Object.entries(cell.data || {})) td.dataset[k] = v;
      } else {
        td.textContent = cell;
      }
      tr.appendChild(td);
    }
    body.appendChild(tr);
  }
}

function render(state) {
  const w = state.world || {};
  const e = state.executor || {};
  const p = state.progress || {};
  drawView(document.getElementById('top-view'), w, 0, 1);
  drawView(document.getElementById('side-view'), w, 0, 2);
  drawCurve(document.getElementById('curve'), e.curve || [], e.boxes_total || p.boxes_total);
  drawStrategy(document.getElementById('strategy'), e.strategy, e.active_node);
  document.getElementById('action').textContent = e.action || '–';
  document.getElementById('subaction').textContent = e.subaction || '–';
  const total = e.boxes_total || p.boxes_total;
  const done = p.boxes_unloaded !== undefined ? p.boxes_unloaded : e.boxes_unloaded;
  document.getElementById('boxes').textContent = total ? `${done} / ${total}` : '–';
  document.getElementById('robot-time').textContent = `${fmt(e.robot_time_s, 1)} s`;
  document.getElementById('sim-time').textContent = `${fmt(p.sim_time_s, 1)} s`;
  fillTable('modes', (e.modes || []).map((m) => [
    m.mode, {text: m.queries, cls: 'n'}, {text: m.failures, cls: 'n'},
    {text: fmt(m.mean_ms, 1), cls: 'n'}, {text: fmt(m.mean_expansions, 0), cls: 'n'}]));
  const topics = [], nodes = [];
  for (const k of state.kernels || []) {
    for (const t of k.topics) {
      topics.push([k.kernel, t.name, {text: t.messages, cls: 'n'},
                   {text: fmt(t.rate_hz, 1), cls: 'n rate', data: {rate: t.rate_hz}},
                   {text: fmt(t.latency_mean_us, 1), cls: 'n'},
                   {text: fmt(t.latency_max_us, 1), cls: 'n'}, {text: t.drops, cls: 'n'}]);
    }
    for (const n of k.nodes) {
      nodes.push([k.kernel, n.name, n.plugin, n.kind, n.host, {text: n.state, cls: 'state'}]);
    }
  }
  fillTable('topics', topics);
  fillTable('nodes', nodes);
  const s = state.server || {};
  document.getElementById('server').textContent =
      `${s.clients || 0} client(s), ${s.sent || 0} sent, ${s.dropped || 0} dropped`;
  document.body.dataset.version = state.version;
}

function connect() {
  const token = new URLSearchParams(location.search).get('token');
  const url = `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws` +
      (token ? `?token=${encodeURIComponent(token)}` : '');
  const ws = new WebSocket(url);
  const status = document.getElementById('connection');
  ws.onopen = () => { status.textContent = 'live'; status.className = 'up'; };
  ws.onmessage = (m) => render(JSON.parse(m.data));
  ws.onclose = () => {
    status.textContent = 'disconnected, retrying';
    status.className = 'down';
    setTimeout(connect, 2000);
  };
}

connect();
