'use strict';
var FF = {};
FF.errors = [];
window.addEventListener('error', function (e) {
  FF.errors.push(String(e.message));
  document.body.setAttribute('data-errors', FF.errors.join(' | '));
});
FF.D = JSON.parse(document.getElementById('ff-data').textContent);
FF.$ = function (id) { return document.getElementById(id); };
FF.esc = function (s) {
  return String(s).replace(/[&<>"]/g, function (c) { return {'&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;'}[c]; });
};
FF.fmt = function (v, d) { return v === undefined || v === null || !isFinite(v) ? 'n/a' : Number(v).toFixed(d); };
FF.VIRIDIS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
FF.cmapRgb = function (t) {
  var V = FF.VIRIDIS; t = Math.max(0, Math.min(1, isFinite(t) ? t : 0));
  var x = t * (V.length - 1), i = Math.min(Math.floor(x), V.length - 2), f = x - i;
  return [0, 1, 2].map(function (k) { return Math.round(V[i][k] + f * (V[i + 1][k] - V[i][k])); });
};
FF.cmap = function (t) { return 'rgb(' + FF.cmapRgb(t).join(',') + ')'; };
FF.PALETTE = ['#4e79a7', '#f28e2b', '#e15759', '#76b7b2', '#59a14f', '#edc948', '#b07aa1', '#ff9da7', '#9c755f', '#bab0ac'];

FF.ticks = function (lo, hi, n) {
  var span = hi - lo, step = Math.pow(10, Math.floor(Math.log10(span / n))), r = span / n / step;
  if (r >= 7.5) step *= 10; else if (r >= 3.5) step *= 5; else if (r >= 1.5) step *= 2;
  var out = [], digits = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
  for (var k = Math.ceil(lo / step - 1e-9); k * step <= hi + 1e-9 * span; ++k) out.push((k * step).toFixed(digits));
  return out;
};
FF.range = function (values, pad) {
  var lo = Infinity, hi = -Infinity;
  values.forEach(function (v) { if (v !== null && isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); } });
  if (!isFinite(lo)) { lo = 0; hi = 1; }
  if (hi - lo < 1e-9) { var c = lo; lo = c - 0.5 * (Math.abs(c) || 1); hi = c + 0.5 * (Math.abs(c) || 1); }
  var p = (hi - lo) * (pad || 0);
  return [lo - p, hi + p];
};
// Axes, ticks and labels of a W x H plot; returns scales and the SVG text of the frame.
FF.axes = function (W, H, xr, yr, xlabel, ylabel) {
  var m = {l: 54, r: 12, t: 8, b: 34};
  var sx = function (x) { return m.l + (x - xr[0]) / (xr[1] - xr[0]) * (W - m.l - m.r); };
  var sy = function (y) { return H - m.b - (y - yr[0]) / (yr[1] - yr[0]) * (H - m.t - m.b); };
  var s = '<rect x="' + m.l + '" y="' + m.t + '" width="' + (W - m.l - m.r) + '" height="' + (H - m.t - m.b) +
          '" fill="#fbfbfc" stroke="#d5d8de"/>';
  FF.ticks(xr[0], xr[1], 6).forEach(function (v) {
    var x = sx(v).toFixed(1);
    s += '<line x1="' + x + '" x2="' + x + '" y1="' + m.t + '" y2="' + (H - m.b) + '" stroke="#eceef1"/>' +
         '<text x="' + x + '" y="' + (H - m.b + 14) + '" text-anchor="middle">' + v + '</text>';
  });
  FF.ticks(yr[0], yr[1], 5).forEach(function (v) {
    var y = sy(v).toFixed(1);
    s += '<line x1="' + m.l + '" x2="' + (W - m.r) + '" y1="' + y + '" y2="' + y + '" stroke="#eceef1"/>' +
         '<text x="' + (m.l - 4) + '" y="' + (+y + 4) + '" text-anchor="end">' + v + '</text>';
  });
  s += '<text x="' + ((m.l + W - m.r) / 2) + '" y="' + (H - 4) + '" text-anchor="middle">' + FF.esc(xlabel) + '</text>' +
       '<text transform="translate(12,' + ((m.t + H - m.b) / 2) + ') rotate(-90)" text-anchor="middle">' +
       FF.esc(ylabel) + '</text>';
  return {sx: sx, sy: sy, svg: s, m: m};
};
// A panel holding one SVG plot; data-n says how many data points it drew.
FF.panel = function (host, title, W, H, inner, n, extra) {
  var div = document.createElement('div');
  div.className = 'panel plot';
  div.setAttribute('data-n', n);
  div.innerHTML = '<div class="title">' + FF.esc(title) + '</div><svg width="' + W + '" height="' + H + '">' + inner +
                  '</svg>' + (extra || '');
  host.appendChild(div);
  return div;
};
// Lines y(x) with gaps at nulls.
FF.linePlot = function (host, title, x, series, xlabel, ylabel) {
  var W = 640, H = 230, all = [], n = 0;
  series.forEach(function (s) { all = all.concat(s.y); });
  var a = FF.axes(W, H, FF.range(x), FF.range(all.concat([0]), 0.05), xlabel, ylabel), inner = a.svg;
  series.forEach(function (s) {
    var d = '', pen = false;
    s.y.forEach(function (v, i) {
      if (v === null || !isFinite(v)) { pen = false; return; }
      d += (pen ? 'L' : 'M') + a.sx(x[i]).toFixed(1) + ' ' + a.sy(v).toFixed(1);
      pen = true; ++n;
    });
    inner += '<path d="' + d + '" fill="none" stroke="' + s.color + '" stroke-width="1.5"/>';
  });
  var legend = '<div class="legend">' + series.map(function (s) {
    return '<span><i class="sw" style="background:' + s.color + '"></i>' + FF.esc(s.name) + '</span>';
  }).join('') + '</div>';
  return FF.panel(host, title, W, H, inner, n, legend);
};

FF.headline = function () {
  var D = FF.D, h = D.headline || {}, T = D.timings;
  var seqName = (D.sequence || '').replace(/\/+$/, '').split('/').pop() || 'run';
  FF.$('title').textContent = 'flowfusion report: ' + seqName;
  FF.$('paths').textContent = 'run ' + D.run_dir + (D.sequence ? ' \u00b7 sequence ' + D.sequence : '') +
                              (D.sequence_note ? ' (' + D.sequence_note + ')' : '');
  var totals = [];
  if (T) T.t.forEach(function (_, i) {
    var s = 0; T.stages.forEach(function (st) { s += st.ms[i] || 0; }); totals.push(s);
  });
  var sorted = totals.slice().sort(function (a, b) { return a - b; });
  var mean = totals.reduce(function (a, b) { return a + b; }, 0) / Math.max(1, totals.length);
  var med = sorted.length ? (sorted[(sorted.length - 1) >> 1] + sorted[sorted.length >> 1]) / 2 : null;
  var cards = [
    ['frames', h.frames, h.complete === false ? 'incomplete: ' + (h.stop_reason || '') : 'complete run'],
    ['ATE RMSE', h.ate_rmse_m !== undefined ? FF.fmt(h.ate_rmse_m * 1000, 1) + ' mm' : 'n/a',
     h.ate_poses ? h.ate_poses + ' poses, max ' + FF.fmt(h.ate_max_m * 1000, 1) + ' mm' : (h.ate_note || 'no ground truth')],
    ['RPE translation', h.rpe_translation_rmse_m !== undefined ? FF.fmt(h.rpe_translation_rmse_m * 1000, 1) + ' mm' : 'n/a',
     h.rpe_delta_s !== undefined ? 'RMSE over ' + FF.fmt(h.rpe_delta_s, 2) + ' s' : (h.rpe_note || 'no ground truth')],
    ['RPE rotation', h.rpe_rotation_rmse_deg !== undefined ? FF.fmt(h.rpe_rotation_rmse_deg, 2) + '\u00b0' : 'n/a',
     h.rpe_delta_s !== undefined ? 'RMSE over ' + FF.fmt(h.rpe_delta_s, 2) + ' s' : ''],
    ['mean IoU (dynamic)', h.mean_iou !== undefined ? FF.fmt(h.mean_iou, 3) : 'n/a',
     h.seg_frames ? h.seg_frames + ' frames, precision ' + FF.fmt(h.mean_precision, 2) + ', recall ' + FF.fmt(h.mean_recall, 2)
                  : 'no ground-truth masks'],
    ['ms per frame', totals.length ? FF.fmt(mean, 1) : 'n/a', totals.length ? 'mean; median ' + FF.fmt(med, 1) +
     ', ' + FF.fmt(1000 / mean, 1) + ' fps' : 'no timings.csv'],
    ['peak memory', h.peak_memory_mib !== undefined ? FF.fmt(h.peak_memory_mib, 0) + ' MiB' : 'n/a', 'resident set'],
    ['tracking failures', h.tracking_failures !== undefined ? h.tracking_failures : 'n/a',
     h.flow_restarts !== undefined ? h.flow_restarts + ' flow restarts' : ''],
    ['map', h.map_surfels !== undefined ? h.map_surfels + ' surfels' : 'n/a',
     h.map_budget_reached ? 'budget reached' : (D.map ? D.map.count + ' of ' + D.map.total + ' points shown' : '')]
  ];
  FF.$('cards').innerHTML = cards.map(function (c) {
    var bad = (c[0] === 'tracking failures' && c[1] > 0) || (c[0] === 'frames' && h.complete === false);
    return '<div class="card' + (bad ? ' bad' : '') + '"><div class="k">' + FF.esc(c[0]) + '</div><div class="v">' +
           FF.esc(c[1] === undefined ? 'n/a' : c[1]) + '</div><div class="d">' + FF.esc(c[2]) + '</div></div>';
  }).join('');
  var st = D.stage_summary || {}, names = Object.keys(st);
  if (names.length) FF.$('stage-table').innerHTML = '<table class="stages"><tr><th>stage</th><th>median ms</th>' +
    '<th>mean ms</th><th>frames</th></tr>' + names.map(function (k) {
      return '<tr><td>' + FF.esc(k) + '</td><td>' + FF.fmt(st[k].median_ms, 2) + '</td><td>' + FF.fmt(st[k].mean_ms, 2) +
             '</td><td>' + FF.esc(st[k].frames) + '</td></tr>';
    }).join('') + '</table>';
  if (h.notes && h.notes.length) FF.$('notes').innerHTML = h.notes.map(function (n) {
    return '<div class="note">note: ' + FF.esc(n) + '</div>';
  }).join('');
  FF.$('config').textContent = D.config || 'no config.json in the run folder';
};

// One projection of the trajectory: ground truth grey, estimate coloured by its per-pose error.
FF.trajView = function (host, title, a, b, la, lb, maxErr) {
  var T = FF.D.trajectory, W = 390, H = 360, est = T.est, gt = T.gt || [], err = T.err_t_m;
  var xs = est.map(function (p) { return p[a]; }).concat(gt.map(function (p) { return p[a]; }));
  var ys = est.map(function (p) { return p[b]; }).concat(gt.map(function (p) { return p[b]; }));
  var xr = FF.range(xs, 0.06), yr = FF.range(ys, 0.06);
  // Equal scale on both axes: widen the narrower range.
  var ux = (xr[1] - xr[0]) / (W - 66), uy = (yr[1] - yr[0]) / (H - 42), u = Math.max(ux, uy);
  var cx = (xr[0] + xr[1]) / 2, cy = (yr[0] + yr[1]) / 2;
  xr = [cx - u * (W - 66) / 2, cx + u * (W - 66) / 2]; yr = [cy - u * (H - 42) / 2, cy + u * (H - 42) / 2];
  var ax = FF.axes(W, H, xr, yr, la + ' (m)', lb + ' (m)'), s = ax.svg, n = 0;
  if (gt.length) s += '<path d="' + gt.map(function (p, i) {
    return (i ? 'L' : 'M') + ax.sx(p[a]).toFixed(1) + ' ' + ax.sy(p[b]).toFixed(1);
  }).join('') + '" fill="none" stroke="#9aa1ad" stroke-width="2" stroke-dasharray="5 3"/>';
  for (var i = 1; i < est.length; ++i) {
    var e = err ? err[i] : null;
    var col = err ? (e === null ? '#c0c4cc' : FF.cmap(e / maxErr)) : '#e8590c';
    s += '<line x1="' + ax.sx(est[i - 1][a]).toFixed(1) + '" y1="' + ax.sy(est[i - 1][b]).toFixed(1) + '" x2="' +
         ax.sx(est[i][a]).toFixed(1) + '" y2="' + ax.sy(est[i][b]).toFixed(1) + '" stroke="' + col +
         '" stroke-width="2.5" stroke-linecap="round"/>';
    ++n;
  }
  if (est.length) s += '<circle cx="' + ax.sx(est[0][a]).toFixed(1) + '" cy="' + ax.sy(est[0][b]).toFixed(1) +
                       '" r="4" fill="#1d2330"><title>start</title></circle>';
  return FF.panel(host, title, W, H, s, n);
};

FF.colourBar = function (host, maxErr) {
  var W = 84, H = 360, s = '';
  for (var k = 0; k < 40; ++k)
    s += '<rect x="10" y="' + (20 + (39 - k) * 8) + '" width="18" height="8.5" fill="' + FF.cmap(k / 39) + '"/>';
  s += '<text x="32" y="28">' + FF.fmt(maxErr * 1000, 1) + ' mm</text><text x="32" y="340">0 mm</text>' +
       '<text x="10" y="14">error</text>';
  var div = document.createElement('div');
  div.className = 'panel';
  div.innerHTML = '<svg width="' + W + '" height="' + H + '">' + s + '</svg>';
  host.appendChild(div);
};

FF.trajectory = function () {
  var T = FF.D.trajectory, views = FF.$('traj-views');
  if (!T || !T.est.length) { FF.$('traj-note').textContent = 'the trajectory is empty'; return; }
  var maxErr = 0;
  if (T.err_t_m) T.err_t_m.forEach(function (e) { if (e !== null) maxErr = Math.max(maxErr, e); });
  FF.$('traj-note').textContent = T.aligned
    ? 'Estimate aligned onto the ground truth (rotation and translation, as the ATE), coloured by its position error; grey dashed: ground truth.'
    : 'No ground truth: the estimated camera path alone (give --sequence with a groundtruth.txt for errors).';
  FF.trajView(views, 'top (x-y)', 0, 1, 'x', 'y', maxErr || 1);
  FF.trajView(views, 'front (x-z)', 0, 2, 'x', 'z', maxErr || 1);
  FF.trajView(views, 'side (y-z)', 1, 2, 'y', 'z', maxErr || 1);
  if (!T.aligned) return;
  FF.colourBar(views, maxErr || 1);
  var host = FF.$('traj-errors');
  FF.linePlot(host, 'translation error over time', T.t,
              [{name: 'position error (mm)', color: '#4e79a7', y: T.err_t_m.map(function (e) { return e === null ? null : e * 1000; })}],
              'time (s)', 'mm');
  FF.linePlot(host, 'rotation error over time', T.t,
              [{name: 'rotation drift since the first pose (deg)', color: '#e15759', y: T.err_r_deg}],
              'time (s)', 'deg');
};

// Stacked per-stage time per frame; hovering a frame lists its stages.
FF.timing = function () {
  var T = FF.D.timings, host = FF.$('timing');
  if (!T || !T.t.length) { host.innerHTML = '<div class="note">no timings.csv in the run folder</div>'; return; }
  var nF = T.t.length, W = Math.min(1340, Math.max(700, host.clientWidth || 1340)), H = 300, tops = [];
  var base = new Array(nF).fill(0), layers = T.stages.map(function (st) {
    var lo = base.slice(); base = base.map(function (b, i) { return b + (st.ms[i] || 0); });
    return {name: st.name, lo: lo, hi: base.slice()};
  });
  tops = base;
  var x = tops.map(function (_, i) { return i; });
  var ax = FF.axes(W, H, [-0.5, nF - 0.5], FF.range(tops.concat([0]), 0.04), 'frame', 'ms'), s = ax.svg;
  var bw = Math.max(1, (ax.sx(1) - ax.sx(0)));
  layers.forEach(function (L, k) {
    var d = '';
    x.forEach(function (i) { d += (i ? 'L' : 'M') + (ax.sx(i) - bw / 2).toFixed(1) + ' ' + ax.sy(L.hi[i]).toFixed(1) +
                                  'L' + (ax.sx(i) + bw / 2).toFixed(1) + ' ' + ax.sy(L.hi[i]).toFixed(1); });
    for (var i = nF - 1; i >= 0; --i) d += 'L' + (ax.sx(i) + bw / 2).toFixed(1) + ' ' + ax.sy(L.lo[i]).toFixed(1) +
                                         'L' + (ax.sx(i) - bw / 2).toFixed(1) + ' ' + ax.sy(L.lo[i]).toFixed(1);
    s += '<path d="' + d + 'Z" fill="' + FF.PALETTE[k % FF.PALETTE.length] + '" stroke="none"/>';
  });
  x.forEach(function (i) {
    var tip = 'frame ' + i + ' (t = ' + FF.fmt(T.t[i], 2) + ' s): ' + FF.fmt(tops[i], 1) + ' ms\n' +
              T.stages.map(function (st) { return st.name + ' ' + FF.fmt(st.ms[i], 1); }).join('\n');
    s += '<rect x="' + (ax.sx(i) - bw / 2).toFixed(1) + '" y="' + ax.m.t + '" width="' + bw.toFixed(2) + '" height="' +
         (H - ax.m.t - ax.m.b) + '" fill="transparent"><title>' + FF.esc(tip) + '</title></rect>';
  });
  var legend = '<div class="legend">' + T.stages.map(function (st, k) {
    return '<span><i class="sw" style="background:' + FF.PALETTE[k % FF.PALETTE.length] + '"></i>' + FF.esc(st.name) + '</span>';
  }).join('') + '</div>';
  FF.panel(host, 'time per frame, stacked by stage (hover a frame for its stages)', W, H, s, nF, legend);
};

FF.filmstrip = function () {
  var F = FF.D.filmstrip || [], host = FF.$('filmstrip');
  if (!F.length) { host.innerHTML = '<div class="note">no masks/ in the run folder</div>'; return; }
  var caption = function (f) {
    return 'frame ' + f.index + ' \u00b7 ' + FF.fmt(f.timestamp, 3) + ' s \u00b7 dynamic ' + FF.fmt(f.area * 100, 1) + '%' +
           (f.iou !== undefined ? ' \u00b7 IoU ' + FF.fmt(f.iou, 2) : '');
  };
  ['evenly spaced', 'largest dynamic area'].forEach(function (why) {
    var items = F.map(function (f, k) { return [f, k]; }).filter(function (p) { return p[0].why === why; });
    if (!items.length) return;
    var div = document.createElement('div');
    div.innerHTML = '<div class="panel"><div class="title">' + FF.esc(why) + '</div><div class="film">' +
      items.map(function (p) {
        return '<figure data-k="' + p[1] + '"><img alt="frame ' + p[0].index + '" src="' + p[0].thumb + '"><figcaption>' +
               FF.esc(caption(p[0])) + '</figcaption></figure>';
      }).join('') + '</div></div>';
    host.appendChild(div);
  });
  var modal = FF.$('modal');
  host.addEventListener('click', function (e) {
    var fig = e.target.closest('figure');
    if (!fig) return;
    var f = F[+fig.getAttribute('data-k')];
    modal.innerHTML = '<div class="imgs"><figure><img alt="estimated" src="' + f.large + '"><figcaption>estimated mask</figcaption></figure>' +
      (f.gt ? '<figure><img alt="ground truth" src="' + f.gt + '"><figcaption>ground-truth mask</figcaption></figure>' : '') +
      '</div><p>' + FF.esc(caption(f)) + (f.gt ? '' : ' \u00b7 no ground-truth mask for this frame') +
      ' \u00b7 click or Esc to close</p>';
    modal.className = 'open';
  });
  modal.addEventListener('click', function () { modal.className = ''; });
  document.addEventListener('keydown', function (e) { if (e.key === 'Escape') modal.className = ''; });
};

// Decodes the int16-quantised points into a Float32Array of positions.
FF.mapPositions = function (M) {
  var bin = atob(M.points_int16), n = bin.length / 6, view = new DataView(new ArrayBuffer(bin.length));
  for (var i = 0; i < bin.length; ++i) view.setUint8(i, bin.charCodeAt(i));
  var pos = new Float32Array(n * 3);
  for (var k = 0; k < n * 3; ++k) {
    var a = k % 3;
    pos[k] = M.lo[a] + (view.getInt16(2 * k, true) + 32768) / 65535 * (M.hi[a] - M.lo[a]);
  }
  return pos;
};
FF.pathLine = function (pts, color) {
  var g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(new Float32Array([].concat.apply([], pts)), 3));
  return new THREE.Line(g, new THREE.LineBasicMaterial({color: color}));
};
FF.frusta = function (keyframes, d) {
  var w = d * 0.6, h = d * 0.45, c = [[0, 0, 0], [-w, -h, d], [w, -h, d], [w, h, d], [-w, h, d]];
  var pairs = [[0, 1], [0, 2], [0, 3], [0, 4], [1, 2], [2, 3], [3, 4], [4, 1]], out = [];
  keyframes.forEach(function (m) {
    var M = new THREE.Matrix4().fromArray(m);
    var wc = c.map(function (p) { return new THREE.Vector3(p[0], p[1], p[2]).applyMatrix4(M); });
    pairs.forEach(function (p) { out.push(wc[p[0]].x, wc[p[0]].y, wc[p[0]].z, wc[p[1]].x, wc[p[1]].y, wc[p[1]].z); });
  });
  var g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(out), 3));
  return new THREE.LineSegments(g, new THREE.LineBasicMaterial({color: 0xff8c1a}));
};
// Pixels of the drawing buffer that differ from the background.
FF.litPixels = function (renderer) {
  var gl = renderer.getContext(), w = gl.drawingBufferWidth, h = gl.drawingBufferHeight, px = new Uint8Array(w * h * 4), n = 0;
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  for (var i = 0; i < px.length; i += 4) if (Math.abs(px[i] - 17) + Math.abs(px[i + 1] - 20) + Math.abs(px[i + 2] - 24) > 24) ++n;
  return n;
};
FF.view3d = function () {
  var M = FF.D.map, host = FF.$('view3d');
  if (!M) {
    FF.$('map-note').textContent = 'no map_points.ply in the run folder';
    host.setAttribute('data-drawn-points', 0);
    host.style.display = 'none';
    return;
  }
  FF.$('map-note').textContent = M.count + ' of the map\u2019s ' + M.total + ' points, coloured by height; ' +
                                 M.keyframes.length + ' keyframe frusta.';
  var W = host.clientWidth || 1200, H = host.clientHeight || 560, renderer;
  try {
    renderer = new THREE.WebGLRenderer({antialias: false, preserveDrawingBuffer: true});
  } catch (e) {
    FF.$('map-note').textContent = 'this browser has no WebGL: ' + e.message;
    host.setAttribute('data-drawn-points', 0);
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(W, H);
  renderer.setClearColor(0x111418);
  host.insertBefore(renderer.domElement, host.firstChild);
  var pos = FF.mapPositions(M), up = new THREE.Vector3(M.up[0], M.up[1], M.up[2]), n = pos.length / 3;
  var hts = new Float32Array(n), hlo = Infinity, hhi = -Infinity;
  for (var i = 0; i < n; ++i) { hts[i] = pos[3 * i] * up.x + pos[3 * i + 1] * up.y + pos[3 * i + 2] * up.z; }
  var sorted = hts.slice().sort();  // a typed array sorts numerically
  hlo = sorted[Math.floor(0.02 * (n - 1))]; hhi = sorted[Math.floor(0.98 * (n - 1))];
  var col = new Float32Array(n * 3);
  for (i = 0; i < n; ++i) {
    var c = FF.cmapRgb((hts[i] - hlo) / Math.max(1e-6, hhi - hlo));
    col[3 * i] = c[0] / 255; col[3 * i + 1] = c[1] / 255; col[3 * i + 2] = c[2] / 255;
  }
  var g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  g.setAttribute('color', new THREE.BufferAttribute(col, 3));
  var lo = new THREE.Vector3().fromArray(M.lo), hi = new THREE.Vector3().fromArray(M.hi);
  var extent = hi.clone().sub(lo).length(), centre = lo.clone().add(hi).multiplyScalar(0.5);
  var points = new THREE.Points(g, new THREE.PointsMaterial({size: extent * 0.004, vertexColors: THREE.VertexColors}));
  var scene = new THREE.Scene();
  scene.add(points);
  var camera = new THREE.PerspectiveCamera(50, W / H, extent * 0.002, extent * 20);
  camera.up.copy(up);
  // Start a little behind and above the first camera, looking at the map's centre: the scene as the
  // run first saw it, with the camera path in front (a view from outside a room sees its walls).
  var start = M.path.length ? new THREE.Vector3().fromArray(M.path[0]) : centre.clone().add(new THREE.Vector3(extent, 0, 0));
  var away = start.clone().sub(centre);
  if (away.length() < 0.05 * extent) away.set(1, 0, 0).multiplyScalar(0.3 * extent);
  camera.position.copy(start).add(away.multiplyScalar(1.0)).add(up.clone().multiplyScalar(0.3 * extent));
  camera.lookAt(centre);
  renderer.render(scene, camera);
  host.setAttribute('data-lit-pixels', FF.litPixels(renderer));  // the points alone
  host.setAttribute('data-drawn-points', n);
  if (M.gt_path.length > 1) scene.add(FF.pathLine(M.gt_path, 0x9aa1ad));
  if (M.path.length > 1) scene.add(FF.pathLine(M.path, 0xff8c1a));
  scene.add(FF.frusta(M.keyframes, extent * 0.025));
  var controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();
  controls.addEventListener('change', function () { renderer.render(scene, camera); });
  renderer.render(scene, camera);
};

['headline', 'trajectory', 'timing', 'filmstrip', 'view3d'].forEach(function (section) {
  try { FF[section](); } catch (e) {
    FF.errors.push(section + ': ' + e.message);
    document.body.setAttribute('data-errors', FF.errors.join(' | '));
    console.error(e);
  }
});
document.body.setAttribute('data-render-ms', Math.round(performance.now()));
document.body.setAttribute('data-ready', '1');
