// engage's report pages (engine/report/HtmlPage.h, engine/run/RunReport.h): inlined into
// every report.html with the page's data (<script id="engage-data">), drawn here with
// dygraphs (plots) and three.js (3D view), both inlined from Debian's packages.
//
// When the page is drawn, <body> gets data-ready="1" and these for the tests
// (tests/apps/report_browser.py): data-errors (script errors), data-plots (plots drawn),
// data-plot-pixels (painted pixels of the least painted plot), data-view-pixels (pixels of
// the 3D view that are not background), data-draw-ms (time to draw, from reading the data).
(function () {
  'use strict';
  var started = window.performance ? performance.now() : 0;
  var data = JSON.parse(document.getElementById('engage-data').textContent);

  // ---- small helpers ------------------------------------------------------------------
  function el(tag, attrs) {
    var e = document.createElement(tag);
    if (attrs)
      Object.keys(attrs).forEach(function (k) {
        if (k === 'text') e.textContent = attrs[k];
        else if (k === 'html') e.innerHTML = attrs[k];
        else if (k === 'class') e.className = attrs[k];
        else e.setAttribute(k, attrs[k]);
      });
    for (var i = 2; i < arguments.length; ++i) {
      var c = arguments[i];
      if (c === null || c === undefined) continue;
      e.appendChild(typeof c === 'string' ? document.createTextNode(c) : c);
    }
    return e;
  }
  // Four significant digits (no exponent for everyday sizes).
  function fmt(v) {
    if (v === null || v === undefined || !isFinite(v)) return '–';
    if (v === 0) return '0';
    var a = Math.abs(v);
    if (a >= 1e9 || a < 1e-4) return v.toExponential(3);
    if (a >= 1e4) return String(Math.round(v));
    var s = v.toPrecision(4);
    if (s.indexOf('.') >= 0) s = s.replace(/0+$/, '').replace(/\.$/, '');
    return s;
  }
  function get(obj, path) {
    var parts = path.split('.');
    for (var i = 0; i < parts.length; ++i) {
      if (obj === null || obj === undefined) return undefined;
      obj = obj[parts[i]];
    }
    return obj;
  }
  // A number of summary.json shown on the page: the tests compare it with the file.
  // `scale` (e.g. 100 for a fraction shown in %) is recorded as data-scale.
  function num(path, unit, root, scale) {
    var v = get(root || S, path);
    var attrs = {'data-key': path, 'data-value': String(v)};
    if (scale) attrs['data-scale'] = String(scale);
    var span = el('span', attrs, fmt(scale && v !== null && v !== undefined ? v * scale : v));
    var out = el('span', null, span);
    if (unit) out.appendChild(document.createTextNode(' ' + unit));
    return out;
  }
  function seconds(path) {
    var v = get(S, path);
    var span = num(path, 's');
    if (isFinite(v) && v >= 120) {
      var m = Math.floor(v / 60), s = Math.round(v - 60 * m);
      span.appendChild(document.createTextNode(' (' + m + ' min ' + s + ' s)'));
    }
    return span;
  }
  function card(label, big, small) {
    return el('div', {class: 'card'}, el('div', {class: 'label'}, label),
              el('div', {class: 'big'}, big), small ? el('div', {class: 'small'}, small) : null);
  }
  function section(title, id) {
    var s = el('section', id ? {id: id} : null, el('h2', {text: title}));
    main.appendChild(s);
    return s;
  }
  function b64(text, Type) {
    var bin = atob(text), bytes = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }
  function tableOf(head, rows) {
    var t = el('table', {class: 'data'});
    var tr = el('tr');
    head.forEach(function (h) { tr.appendChild(el('th', {text: h})); });
    t.appendChild(el('thead', null, tr));
    var body = el('tbody');
    rows.forEach(function (r) {
      var row = el('tr');
      r.forEach(function (c) {
        var td = el('td');
        if (c instanceof Node) {
          td.appendChild(c);
          if (c.querySelector && c.querySelector('[data-key]')) td.className = 'n';
        } else td.textContent = c === undefined ? '' : String(c);
        row.appendChild(td);
      });
      body.appendChild(row);
    });
    t.appendChild(body);
    return t;
  }

  // mm^3/min -> mm³/min for reading.
  function pretty(unit) {
    return String(unit || '').replace(/\^3/g, '\u00b3').replace(/\^2/g, '\u00b2');
  }
  var S = data.summary || {};
  var U = {};
  Object.keys(data.units || {}).forEach(function (k) { U[k] = pretty(data.units[k]); });
  var header = el('header', null, el('h1', {text: data.title || 'engage report'}));
  document.body.appendChild(header);
  var main = el('main');
  document.body.appendChild(main);

  // ---- a batch ------------------------------------------------------------------------
  function renderBatch() {
    var B = data.batch;
    header.appendChild(el('div', {class: 'sub'}, B.subtitle || ''));
    var counts = {};
    B.jobs.forEach(function (j) { counts[j.status] = (counts[j.status] || 0) + 1; });
    var cards = el('div', {class: 'cards'});
    cards.appendChild(card('jobs', el('span', {'data-count': 'all'}, String(B.jobs.length))));
    Object.keys(counts).sort().forEach(function (k) {
      cards.appendChild(card(k, el('span', {'data-count': k}, String(counts[k]))));
    });
    section('Jobs').appendChild(cards);
    if (B.statements && B.statements.length) {
      var ul = el('ul');
      B.statements.forEach(function (t) { ul.appendChild(el('li', {text: t})); });
      var measured = section('What was measured');
      measured.appendChild(ul);
      main.insertBefore(measured, main.firstChild);
    }
    // Columns: those with a value in some row.
    var columns = [['job', null], ['status', null], ['program', null], ['removed', 'removed', pretty(B.units.volume)],
                   ['cutting time', 'cutting_time_s', 's'], ['peak MRR', 'peak_mrr', pretty(B.units.mrr)],
                   ['at line', 'peak_mrr_line'], ['feed time before schedule', 'feed_time_before_s', 's'],
                   ['after', 'feed_time_after_s', 's'], ['collisions', 'collisions']];
    columns = columns.filter(function (c) {
      return !c[1] || B.jobs.some(function (j) {
        return j.figures && j.figures[c[1]] !== undefined && j.figures[c[1]] !== null;
      });
    });
    var rows = B.jobs.map(function (j) {
      var status = el('span', {class: j.status === 'ok' ? 'status-ok' :
                                   j.status === 'failed' ? 'status-failed' : 'status-other'},
                      j.status);
      var name = j.report ? el('a', {href: j.report}, j.name) : el('span', null, j.name);
      var notes = el('span', null, el('span', {title: j.program || ''}, (j.program || '').split('/').pop()));
      if (j.warnings && j.warnings.length)
        notes.appendChild(el('div', {class: 'note', style: 'color: var(--warn)'}, j.warnings.join('; ')));
      if (j.error) notes.appendChild(el('div', {class: 'status-failed job-error'}, j.error));
      return [name, status, notes].concat(columns.slice(3).map(function (c) {
        var v = j.figures ? j.figures[c[1]] : undefined;
        return v !== undefined && v !== null ? num(c[1], c[2], j.figures) : '';
      }));
    });
    section(B.rows_title || 'One row per job (name: the job\'s own report)').appendChild(el('div', {class: 'scroll'}, tableOf(
        columns.map(function (c) { return c[0]; }), rows)));
    if (B.images && B.images.length) {
      var grid = el('div', {class: 'figures'});
      B.images.forEach(function (f) {
        grid.appendChild(el('figure', null, el('a', {href: f}, el('img', {src: f, alt: f, loading: 'lazy'})),
                            el('figcaption', {text: f})));
      });
      section('Figures').appendChild(grid);
    }
    if (B.files && B.files.length) {
      var s = section('Files');
      B.files.forEach(function (f) { s.appendChild(el('div', null, el('a', {href: f}, f))); });
    }
  }

  // ---- a run --------------------------------------------------------------------------
  var series = data.series || {step: []};
  var rows = series.step.length;
  var charts = [];
  var selectionBox, marker = null, selectStepIn3d = null;

  function sourceText(file, line) {
    var t = data.source ? data.source[file + ':' + line] : undefined;
    return t === undefined ? '' : t;
  }
  function fileName(file) {
    var f = (data.sources || [])[file] || '';
    return f.split('/').pop();
  }

  // Show one step (a row of `table`) in the selection box, the plots and the 3D view.
  function showStep(table, row, fromPlot) {
    var step = table.step[row], file = table.file[row], line = table.line[row];
    selectionBox.innerHTML = '';
    var parts = [el('span', {class: 'where'}, 'step ' + step + ' · ' + fileName(file) + ':' + line +
                                                   ' · T' + table.tool[row]),
                 ' '];
    var text = sourceText(file, line);
    if (text) parts.push(el('code', {text: text}));
    var vals = [];
    function v(name, label, unit) {
      if (table[name] && table[name][row] !== null && table[name][row] !== undefined)
        vals.push(label + ' ' + fmt(table[name][row]) + ' ' + unit);
    }
    v('mrr', 'MRR', U.mrr);
    v('mrr_exact', 'analytic', U.mrr);
    v('feed', 'feed', U.feed);
    v('feed_scheduled', 'scheduled feed', U.feed);
    v('h_max', 'h_max', U.length);
    v('f_peak', 'peak force', U.force);
    v('power', 'power', U.power);
    var line1 = el('div', null);
    parts.forEach(function (p) { line1.appendChild(typeof p === 'string' ? document.createTextNode(p) : p); });
    selectionBox.appendChild(line1);
    selectionBox.appendChild(el('div', {class: 'note'}, vals.join(' · ')));
    if (table.x && selectStepIn3d) selectStepIn3d(table.x[row], table.y[row], table.z[row]);
    if (!fromPlot) {
      // The nearest plotted step.
      var lo = 0, hi = rows - 1;
      while (lo < hi) {
        var mid = (lo + hi) >> 1;
        if (series.step[mid] < step) lo = mid + 1; else hi = mid;
      }
      charts.forEach(function (g) { g.setSelection(lo); });
    }
  }

  function renderSummary() {
    var cmd = data.command;
    header.appendChild(el('div', {class: 'sub'},
                          cmd + ' · ' + (S.program || '') + ' · stock ' + (S.stock || 'none') + ' · ' +
                              (S.stock_model ? S.stock_model + ' model, ' : '') +
                              (S.voxel !== undefined ? 'cell ' + fmt(S.voxel) + ' ' + U.length + ' · ' : '') +
                              'units ' + S.units));
    var cards = el('div', {class: 'cards'});
    if (S.removed !== undefined)
      cards.appendChild(card('Removed', num('removed', U.volume),
                             el('span', null, 'stock ', num('volume_before', U.volume), ' → ',
                                num('volume_after', U.volume))));
    cards.appendChild(card('Cutting time (programmed feeds)', seconds('cutting_time_s'),
                           el('span', null, num('moves'), ' moves, ', num('steps'), ' steps')));
    if (S.schedule) {
      cards.appendChild(card('Cycle time before → after schedule',
                             el('span', null, num('schedule.cycle_time_before_s', 's'), ' → ',
                                num('schedule.cycle_time_after_s', 's')),
                             el('span', null, 'saving ', num('schedule.saving_relative', '%', null, 100),
                                ', largest acceleration ',
                                num('schedule.max_acceleration', U.acceleration))));
    }
    if (S.peak_mrr)
      cards.appendChild(card('Peak MRR', num('peak_mrr.value', U.mrr),
                             el('span', null, 'at line ', num('peak_mrr.line'), ', step ',
                                num('peak_mrr.step'))));
    if (S.physics) {
      var L = {};
      Object.keys(S.physics.unit_labels).forEach(function (k) { L[k] = pretty(S.physics.unit_labels[k]); });
      cards.appendChild(card('Peak force (' + S.physics.material + ')',
                             num('physics.peaks.f_peak.value', L.force),
                             el('span', null, 'at line ', num('physics.peaks.f_peak.line'), '; h_max ',
                                num('physics.peaks.h_max.value', L.chip), ', power ',
                                num('physics.peaks.power.value', L.power))));
      if (S.physics.peaks_scheduled)
        cards.appendChild(card('Peak force after schedule',
                               num('physics.peaks_scheduled.f_peak.value', L.force),
                               el('span', null, 'at line ', num('physics.peaks_scheduled.f_peak.line'))));
    }
    if (S.collisions)
      cards.appendChild(card('Collisions', num('collisions.count'),
                             S.collisions.count ? 'shank, holder or rapid met material' : 'none'));
    if (S.part)
      cards.appendChild(card('Gouges in the part', num('part.gouges.count'),
                             el('span', null, 'deepest ', num('part.gouges.deepest', U.length), '; leftovers ',
                                num('part.leftovers.count'), ', thickest ', num('part.leftovers.thickest', U.length))));
    var s = section('Summary');
    s.appendChild(cards);

    if (S.tools && S.tools.length) {
      s.appendChild(el('h2', {text: 'Tools', style: 'margin-top:14px'}));
      s.appendChild(tableOf(['tool', 'cutter', 'first line', 'steps', 'removed', 'cutting time', 'peak MRR', 'at line'],
                            S.tools.map(function (t, i) {
                              var p = 'tools.' + i + '.';
                              return ['T' + t.number + ' ' + (t.name || ''), t.cutter || '', num(p + 'first_line'),
                                      num(p + 'steps'), num(p + 'removed', U.volume),
                                      num(p + 'cutting_time_s', 's'), num(p + 'peak_mrr.value', U.mrr),
                                      num(p + 'peak_mrr.line')];
                            })));
    }
    if ((data.warnings && data.warnings.length) || (S.collisions && S.collisions.count)) {
      var w = section('Warnings and collisions', 'warnings');
      if (data.warnings.length) {
        var ul = el('ul', {class: 'warnings'});
        data.warnings.forEach(function (t) { ul.appendChild(el('li', {text: t})); });
        w.appendChild(ul);
      }
      if (S.collisions && S.collisions.places && S.collisions.places.length)
        w.appendChild(tableOf(['line', 'tool', 'part', 'steps', 'material met'],
                              S.collisions.places.slice(0, 200).map(function (c, i) {
                                var p = 'collisions.places.' + i + '.';
                                return [(c.file ? c.file.split('/').pop() + ':' : '') + c.line, 'T' + c.tool, c.part,
                                        c.first_step + '–' + c.last_step, num(p + 'volume', U.volume)];
                              })));
    }
    if (S.part) {
      // The final stock against the part: the regions beyond the tolerance and the allowance.
      var ps = section('The part: ' + S.part.file.split('/').pop(), 'part');
      ps.appendChild(el('p', {class: 'note'}, num('part.gouges.count'), ' gouge(s) deeper than ',
                        num('part.tolerance', U.length), ' (deepest ', num('part.gouges.deepest', U.length), '), ',
                        num('part.leftovers.count'), ' leftover(s) thicker than ', num('part.allowance', U.length),
                        ' (thickest ', num('part.leftovers.thickest', U.length), '); the deviation read along the part\'s normal at ',
                        num('part.samples'), ' samples of ', num('part.sample_size', U.length),
                        '. The 3D view below colours the stock by it: blue where the part\'s material is gone, red where material is left.'));
      var where = function (r) { return r.at.map(fmt).join(', '); };
      if (S.part.gouges.regions.length)
        ps.appendChild(tableOf(['gouge', 'depth', 'area', 'volume', 'at', 'cut by (the floor\'s area each cut)'],
                               S.part.gouges.regions.map(function (r, i) {
                                 var p = 'part.gouges.regions.' + i + '.';
                                 var lines = el('span');
                                 r.lines.forEach(function (l, k) {
                                   var text = (data.part_lines || {})[(data.sources || []).indexOf(l.file) + ':' + l.line] || '';
                                   var link = el('a', {href: '#step=' + l.first_step, text: l.file.split('/').pop() + ':' + l.line});
                                   link.addEventListener('click', function () { selectNearestStep(l.first_step); });
                                   lines.appendChild(el('div', null, el('b', null, link),
                                                        ' ', el('code', {text: text}), ' (', num(p + 'lines.' + k + '.floor_area', U.area), ')'));
                                 });
                                 return [String(i + 1), num(p + 'depth', U.length), num(p + 'area', U.area),
                                         num(p + 'volume', U.volume), where(r), lines];
                               })));
      if (S.part.leftovers.regions.length)
        ps.appendChild(tableOf(['leftover', 'thickness', 'area', 'volume', 'at'],
                               S.part.leftovers.regions.slice(0, 20).map(function (r, i) {
                                 var p = 'part.leftovers.regions.' + i + '.';
                                 return [String(i + 1), num(p + 'thickness', U.length), num(p + 'area', U.area),
                                         num(p + 'volume', U.volume), where(r)];
                               })));
    }
    if (S.schedule) {
      var sc = section('Schedule: what bound the feed, line by line', 'schedule');
      var v = S.schedule.verified;
      if (v && v.checks && v.checks.length)
        sc.appendChild(tableOf(['limit (re-fed program re-simulated)', 'worst step', 'at re-fed line', 'limit', 'holds'],
                               v.checks.map(function (c, i) {
                                 var p = 'schedule.verified.checks.' + i + '.';
                                 return [c.option, num(p + 'worst', pretty(c.unit)), num(p + 'line'),
                                         num(p + 'limit', pretty(c.unit)), c.holds ? 'yes' : 'NO'];
                               })));
      if (S.schedule.lines && S.schedule.lines.length) {
        sc.appendChild(tableOf(['line', 'programmed feed', 'scheduled, lowest', 'highest', 'bound by (steps)'],
                               S.schedule.lines.map(function (l, i) {
                                 var p = 'schedule.lines.' + i + '.';
                                 var src = (data.sources || [])[l.file] || '';
                                 return [(l.file ? src.split('/').pop() + ':' : '') + l.line,
                                         num(p + 'feed_programmed', U.feed), num(p + 'feed_lowest', U.feed),
                                         num(p + 'feed_highest', U.feed),
                                         l.bound_by.map(function (b) { return b.limit + ' (' + b.steps + ')'; }).join(', ')];
                               })));
        if (S.schedule.lines_count > S.schedule.lines.length)
          sc.appendChild(el('p', {class: 'note'}, 'the first ', String(S.schedule.lines.length), ' of ',
                            String(S.schedule.lines_count), ' lines; steps.csv has every step\'s binding'));
      }
    }
    if (S.agreement_exact) {
      var a = section('Measured against the analytic model (steady-state steps)');
      var pc = function (p) { return num(p, '%', null, 100); };
      a.appendChild(tableOf(['path', 'steps', 'mean |measured / analytic − 1|, exact form', 'largest', 'paper\'s form: mean', 'largest'],
                            ['straight', 'concave', 'convex'].map(function (k) {
                              return [k, num('agreement_exact.' + k + '.steps'),
                                      pc('agreement_exact.' + k + '.mean_relative'),
                                      pc('agreement_exact.' + k + '.max_relative'),
                                      pc('agreement_paper.' + k + '.mean_relative'),
                                      pc('agreement_paper.' + k + '.max_relative')];
                            })));
      if (S.cross_check)
        a.appendChild(el('p', {class: 'note'}, 'cross-check against the ', S.cross_check.other_model,
                         ' model: ', num('cross_check.steps_differing'), ' steps differ by more than ',
                         num('cross_check.tolerance_relative', '%', null, 100), '; removed volumes differ by ',
                         num('cross_check.removed_relative_difference', '%', null, 100)));
    }
  }

  // ---- plots ----------------------------------------------------------------------------
  function renderPlots(parent) {
    var L = U.length;
    var specs = [
      {title: 'MRR along the path', unit: U.mrr,
       cols: [['mrr', 'measured'], ['mrr_exact', 'analytic (exact form)'], ['mrr_scheduled', 'measured × scheduled feed']],
       limit: 'mrr', limitLabel: 'target'},
      {title: 'Feed', unit: U.feed, cols: [['feed', 'programmed'], ['feed_scheduled', 'scheduled']]},
      {title: 'Tangential acceleration (Eq 24)', unit: U.acceleration, cols: [['acceleration', 'scheduled']],
       limit: 'acceleration', limitLabel: 'limit', symmetric: true},
      {title: 'Chip thickness h_max', unit: U.length, cols: [['h_max', 'programmed'], ['h_max_scheduled', 'scheduled']],
       limit: 'h_max', limitLabel: 'limit'},
      {title: 'Peak force', unit: U.force, cols: [['f_peak', 'programmed'], ['f_peak_scheduled', 'scheduled']],
       limit: 'f_peak', limitLabel: 'limit'},
      {title: 'Spindle power', unit: U.power, cols: [['power', 'programmed'], ['power_scheduled', 'scheduled']],
       limit: 'power', limitLabel: 'limit'}];
    var colors = ['#1f5fbf', '#d0661d', '#2a9d54'];
    var changes = [];
    for (var i = 1; i < rows; ++i)
      if (series.tool[i] !== series.tool[i - 1]) changes.push([series.arc[i - 1], 'T' + series.tool[i]]);
    var syncing = false;
    specs.forEach(function (spec) {
      var cols = spec.cols.filter(function (c) { return series[c[0]] !== undefined; });
      if (!cols.length) return;
      var box = el('div', {class: 'chart'});
      var title = el('div', {class: 'title', text: spec.title + ' (' + spec.unit + ')'});
      var plot = el('div', {class: 'plot'});
      var legend = el('div', {class: 'legend'});
      box.appendChild(title);
      box.appendChild(plot);
      box.appendChild(legend);
      parent.appendChild(box);
      var table = new Array(rows);
      for (var r = 0; r < rows; ++r) {
        var row = [series.arc[r]];
        cols.forEach(function (c) { row.push(series[c[0]][r]); });
        table[r] = row;
      }
      var limit = data.limits ? data.limits[spec.limit] : undefined;
      var g = new Dygraph(plot, table, {
        labels: ['path (' + L + ')'].concat(cols.map(function (c) { return c[1]; })),
        colors: colors.slice(0, cols.length),
        strokeWidth: 1.2,
        connectSeparatedPoints: false,
        labelsDiv: legend,
        labelsSeparateLines: false,
        legend: 'always',
        xlabel: 'path (' + L + ')',
        axes: {y: {axisLabelWidth: 60}},
        highlightCircleSize: 3,
        valueFormatter: function (v) { return fmt(v); },
        highlightCallback: function (e, x, pts, row) { showStep(series, row, true); },
        clickCallback: function () {
          // The step stays selected in every plot, and the address names it (#step=N).
          var row = g.getSelection();
          if (row < 0) return;
          charts.forEach(function (o) { if (o !== g) o.setSelection(row); });
          if (history.replaceState) history.replaceState(null, '', '#step=' + series.step[row]);
        },
        underlayCallback: function (ctx, area, gg) {
          ctx.save();
          ctx.setLineDash([4, 4]);
          ctx.strokeStyle = '#888';
          ctx.fillStyle = '#555';
          ctx.font = '11px sans-serif';
          changes.forEach(function (c) {
            var x = gg.toDomXCoord(c[0]);
            ctx.beginPath();
            ctx.moveTo(x, area.y);
            ctx.lineTo(x, area.y + area.h);
            ctx.stroke();
            ctx.fillText(c[1], x + 3, area.y + 11);
          });
          if (limit !== undefined) {
            ctx.strokeStyle = '#b3261e';
            [limit].concat(spec.symmetric ? [-limit] : []).forEach(function (v) {
              var y = gg.toDomYCoord(v);
              ctx.beginPath();
              ctx.moveTo(area.x, y);
              ctx.lineTo(area.x + area.w, y);
              ctx.stroke();
            });
            ctx.fillStyle = '#b3261e';
            ctx.fillText(spec.limitLabel + ' ' + fmt(limit), area.x + 4, gg.toDomYCoord(limit) - 3);
          }
          ctx.restore();
        },
        drawCallback: function (me, initial) {
          if (initial || syncing) return;
          syncing = true;
          var range = me.xAxisRange();
          charts.forEach(function (o) {
            if (o !== me) o.updateOptions({dateWindow: range});
          });
          syncing = false;
        }
      });
      if (limit !== undefined) {
        // Keep the limit in view.
        var top = limit;
        cols.forEach(function (c) {
          series[c[0]].forEach(function (v) { if (v !== null && v > top) top = v; });
        });
        g.updateOptions({valueRange: spec.symmetric ? [-1.1 * top, 1.1 * top] : [0, 1.1 * top]});
      }
      charts.push(g);
    });
    var n = data.series_steps || {};
    parent.appendChild(el('p', {class: 'note'},
                          (n.kept === n.of ? 'every step plotted (' + n.of + ')' :
                                             n.kept + ' of ' + n.of + ' steps plotted: the run cut into ' + n.buckets +
                                                 ' pieces, each with its highest and lowest values, and every peak summary.json names') +
                              '. Drag to zoom (all plots follow), double-click to zoom out; the pointer shows the step and its line; dashed lines: tool changes.'));
  }

  // ---- 3D view ------------------------------------------------------------------------
  var viewPixels = -1;
  function renderView(parent) {
    var surf = data.surface, tab = data.surface_steps;
    var controlsBar = el('div', {class: 'controls'});
    var view = el('div', {id: 'view'});
    parent.appendChild(controlsBar);
    parent.appendChild(view);
    var colorbar = el('div', {class: 'colorbar'});
    parent.appendChild(colorbar);
    var info = el('p', {class: 'note'});
    parent.appendChild(info);
    if (typeof THREE === 'undefined') {
      info.textContent = 'three.js did not load: no 3D view.';
      return;
    }
    var positions = b64(surf.positions, Float32Array);
    var indices = b64(surf.indices, Uint32Array);
    var vrow = b64(surf.vertex_row, Int32Array);
    var canvas = el('canvas');
    view.appendChild(canvas);
    var renderer;
    try {
      renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: true, preserveDrawingBuffer: true});
    } catch (e) {
      info.textContent = 'This browser has no WebGL: no 3D view (' + e.message + ').';
      return;
    }
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    var scene = new THREE.Scene();
    scene.background = new THREE.Color(0xeef0f4);
    var geom = new THREE.BufferGeometry();
    geom.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    geom.setIndex(new THREE.BufferAttribute(indices, 1));
    geom.computeVertexNormals();
    geom.computeBoundingBox();
    var colors = new Float32Array(positions.length);
    geom.setAttribute('color', new THREE.BufferAttribute(colors, 3));
    var material = new THREE.MeshLambertMaterial({vertexColors: THREE.VertexColors, side: THREE.DoubleSide});
    var mesh = new THREE.Mesh(geom, material);
    scene.add(mesh);
    var bb = geom.boundingBox, size = new THREE.Vector3(), center = new THREE.Vector3();
    bb.getSize(size);
    bb.getCenter(center);
    var diag = Math.max(size.length(), 1e-6);
    var camera = new THREE.PerspectiveCamera(35, 1, diag / 1000, diag * 20);
    camera.up.set(0, 0, 1);
    camera.position.set(center.x + 0.9 * diag, center.y - 1.3 * diag, center.z + 1.0 * diag);
    scene.add(new THREE.AmbientLight(0xffffff, 0.45));
    var light = new THREE.DirectionalLight(0xffffff, 0.75);
    camera.add(light);
    light.position.set(0.3, 0.5, 1);
    scene.add(camera);
    var controls = new THREE.OrbitControls(camera, renderer.domElement);
    controls.target.copy(center);
    controls.update();

    // The tool path (plotted steps), hidden until asked for.
    var pathPts = new Float32Array(rows * 3);
    for (var i = 0; i < rows; ++i) {
      pathPts[3 * i] = series.x[i];
      pathPts[3 * i + 1] = series.y[i];
      pathPts[3 * i + 2] = series.z[i];
    }
    var pathGeom = new THREE.BufferGeometry();
    pathGeom.setAttribute('position', new THREE.BufferAttribute(pathPts, 3));
    var path = new THREE.Line(pathGeom, new THREE.LineBasicMaterial({color: 0x203060, transparent: true, opacity: 0.55}));
    path.visible = false;
    scene.add(path);
    marker = new THREE.Mesh(new THREE.SphereBufferGeometry(diag / 90, 16, 12),
                            new THREE.MeshBasicMaterial({color: 0xd01010}));
    marker.visible = false;
    scene.add(marker);

    function resize() {
      var w = view.clientWidth, h = view.clientHeight;
      renderer.setSize(w, h, false);
      camera.aspect = w / Math.max(h, 1);
      camera.updateProjectionMatrix();
      render();
    }
    function render() { renderer.render(scene, camera); }
    controls.addEventListener('change', render);
    window.addEventListener('resize', resize);
    selectStepIn3d = function (x, y, z) {
      marker.position.set(x, y, z);
      marker.visible = true;
      render();
    };

    // Colour by: the measured MRR (and scheduled), the peak force, the tool or the step.
    var modes = [['mrr', 'MRR (' + U.mrr + ')'], ['mrr_scheduled', 'scheduled MRR (' + U.mrr + ')'],
                 ['f_peak', 'peak force (' + U.force + ')'], ['tool', 'tool'], ['step', 'step']];
    modes = modes.filter(function (m) { return tab[m[0]] !== undefined; });
    // With --part: the stock's distance from the part at each vertex, first.
    var deviation = surf.deviation ? b64(surf.deviation, Float32Array) : null;
    if (deviation) modes.unshift(['deviation', 'deviation from the part (' + U.length + ')']);
    var select = el('select', {id: 'colour-by'});
    modes.forEach(function (m) { select.appendChild(el('option', {value: m[0]}, m[1])); });
    var pathBox = el('input', {type: 'checkbox', id: 'show-path'});
    controlsBar.appendChild(el('label', null, 'colour by ', select));
    controlsBar.appendChild(el('label', null, pathBox, ' tool path (plotted steps)'));
    pathBox.addEventListener('change', function () { path.visible = pathBox.checked; render(); });

    var stops = [[0.267, 0.005, 0.329], [0.229, 0.322, 0.546], [0.128, 0.567, 0.551],
                 [0.369, 0.789, 0.383], [0.993, 0.906, 0.144]];  // viridis
    function ramp(t) {
      t = Math.min(1, Math.max(0, t)) * (stops.length - 1);
      var k = Math.min(stops.length - 2, Math.floor(t)), f = t - k, a = stops[k], b = stops[k + 1];
      return [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])];
    }
    var palette = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2', '#7f7f7f', '#bcbd22', '#17becf'];
    function hex(c) { var v = parseInt(c.slice(1), 16); return [(v >> 16 & 255) / 255, (v >> 8 & 255) / 255, (v & 255) / 255]; }
    // Diverging: blue (the part's material gone) through white to red (material left), at
    // +-range: five times the larger of the tolerance and the allowance.
    function paintDeviation() {
      var range = surf.deviation_range;
      var blue = [0.15, 0.3, 0.75], white = [0.96, 0.96, 0.96], red = [0.8, 0.15, 0.12];
      for (var i = 0; i < deviation.length; ++i) {
        var t = Math.max(-1, Math.min(1, deviation[i] / range)), e = t < 0 ? blue : red, f = Math.abs(t);
        for (var k = 0; k < 3; ++k) colors[3 * i + k] = white[k] + f * (e[k] - white[k]);
      }
      geom.attributes.color.needsUpdate = true;
      colorbar.innerHTML = '';
      colorbar.appendChild(el('span', null, fmt(-range) + ' (gouge)'));
      colorbar.appendChild(el('span', {class: 'bar', style: 'background: linear-gradient(to right,rgb(38,77,191),rgb(245,245,245),rgb(204,38,31))'}));
      colorbar.appendChild(el('span', null, fmt(range) + ' (left)'));
      render();
    }
    function paint(mode) {
      if (mode === 'deviation') return paintDeviation();
      var vals = tab[mode], lo = Infinity, hi = -Infinity, tools = {};
      vals.forEach(function (v) {
        if (v === null) return;
        if (v < lo) lo = v;
        if (v > hi) hi = v;
      });
      if (mode !== 'step' && mode !== 'tool') lo = Math.min(lo, 0);
      if (mode === 'tool') {
        var list = [];
        vals.forEach(function (v) { if (!(v in tools)) { tools[v] = list.length; list.push(v); } });
      }
      for (var i = 0; i < vrow.length; ++i) {
        var r = vrow[i], c;
        if (r < 0 || vals[r] === null) c = [0.78, 0.79, 0.81];
        else if (mode === 'tool') c = hex(palette[tools[vals[r]] % palette.length]);
        else c = ramp(hi > lo ? (vals[r] - lo) / (hi - lo) : 1);
        colors[3 * i] = c[0];
        colors[3 * i + 1] = c[1];
        colors[3 * i + 2] = c[2];
      }
      geom.attributes.color.needsUpdate = true;
      colorbar.innerHTML = '';
      if (mode === 'tool') {
        var sw = el('div', {class: 'swatches'});
        Object.keys(tools).forEach(function (t) {
          var c = palette[tools[t] % palette.length];
          sw.appendChild(el('span', {class: 'swatch'}, el('i', {style: 'background:' + c}), 'T' + t));
        });
        sw.appendChild(el('span', {class: 'swatch'}, el('i', {style: 'background:#c7c9cf'}), 'never cut'));
        colorbar.appendChild(sw);
      } else {
        var grad = stops.map(function (s, k) {
          return 'rgb(' + s.map(function (x) { return Math.round(255 * x); }).join(',') + ') ' + (100 * k / (stops.length - 1)) + '%';
        });
        colorbar.appendChild(el('span', null, fmt(lo)));
        colorbar.appendChild(el('span', {class: 'bar', style: 'background: linear-gradient(to right,' + grad.join(',') + ')'}));
        colorbar.appendChild(el('span', null, fmt(hi)));
        colorbar.appendChild(el('span', null, '· grey: never cut'));
      }
      render();
    }
    select.addEventListener('change', function () { paint(select.value); });

    // A click (not a drag) on the stock shows the step that last cut there.
    var raycaster = new THREE.Raycaster(), down = null;
    renderer.domElement.addEventListener('pointerdown', function (e) { down = [e.clientX, e.clientY]; });
    renderer.domElement.addEventListener('pointerup', function (e) {
      if (!down || Math.abs(e.clientX - down[0]) + Math.abs(e.clientY - down[1]) > 4) return;
      var rect = renderer.domElement.getBoundingClientRect();
      var p = new THREE.Vector2((e.clientX - rect.left) / rect.width * 2 - 1, -(e.clientY - rect.top) / rect.height * 2 + 1);
      raycaster.setFromCamera(p, camera);
      var hit = raycaster.intersectObject(mesh)[0];
      if (!hit) return;
      var f = hit.face, best = -1, bestD = Infinity;
      [f.a, f.b, f.c].forEach(function (v) {
        var d = hit.point.distanceTo(new THREE.Vector3(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]));
        if (vrow[v] >= 0 && d < bestD) { bestD = d; best = vrow[v]; }
      });
      if (best < 0) {
        selectionBox.textContent = 'never cut here (stock face)';
        return;
      }
      showStep(tab, best, false);
      marker.position.copy(hit.point);
      render();
    });

    info.textContent = 'The final stock: ' + surf.triangles + ' triangles meshed at a ' + fmt(surf.cell) + ' ' + U.length +
        ' cell, coloured by the last step whose tool surface passes within 1.5 cells of each place. ' +
        'Drag to rotate, wheel to zoom, right-drag to pan; click the stock for the step that cut there.';
    resize();
    paint(modes[0][0]);
    // Pixels that are not background, for the tests.
    var gl = renderer.getContext(), w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    var px = new Uint8Array(4 * w * h);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    var count = 0;
    for (var k = 0; k < px.length; k += 4)
      if (Math.abs(px[k] - 0xee) + Math.abs(px[k + 1] - 0xf0) + Math.abs(px[k + 2] - 0xf4) > 12) ++count;
    viewPixels = count;
  }

  function renderFiles() {
    if (!data.files || !data.files.length) return;
    var s = section('Files of this run');
    var ul = el('ul');
    var what = {'steps.csv': 'one row per step', 'summary.json': 'the figures on this page',
                'removed.vdb': 'the material each step took (grids removed, step, mrr)',
                'stock.vdb': 'the final stock (fractions and surface)', 'stock.stl': 'the final stock as a mesh',
                'gouges.csv': 'the gouges in the part, with the lines that cut them',
                'leftovers.csv': 'the material left on the part',
                'deviation.vdb': 'the stock\'s distance from the part (grid deviation)'};
    data.files.forEach(function (f) {
      ul.appendChild(el('li', null, el('a', {href: f}, f), what[f] ? ' – ' + what[f] : ''));
    });
    s.appendChild(ul);
  }

  function renderRun() {
    renderSummary();
    selectionBox = el('div', {class: 'note'}, 'Point at a plot to see the step, its line of G-code and its values; click the stock in 3D for the step that cut there.');
    var sel = section('Selected step', 'selection');
    sel.appendChild(selectionBox);
    var layout = el('div', {class: 'layout'});
    var left = el('section', null, el('h2', {text: 'Along the path'}));
    layout.appendChild(left);
    main.appendChild(layout);
    if (rows) renderPlots(left);
    else left.appendChild(el('p', {class: 'note'}, 'no steps'));
    if (data.surface) {
      var right = el('section', {id: 'view3d'}, el('h2', {text: 'Final stock in 3D'}));
      layout.appendChild(right);
      renderView(right);
    } else {
      layout.style.gridTemplateColumns = 'minmax(0, 1fr)';
    }
    renderFiles();
    // report.html#step=N opens with step N (or the nearest plotted one) selected.
    var m = /step=(\d+)/.exec(location.hash);
    if (m) selectNearestStep(Number(m[1]));
  }

  // Select step `want`, or the nearest plotted one.
  function selectNearestStep(want) {
    if (!rows) return;
    var row = 0;
    for (var i = 0; i < rows; ++i)
      if (Math.abs(series.step[i] - want) < Math.abs(series.step[row] - want)) row = i;
    showStep(series, row, false);
  }

  function painted(canvas) {
    try {
      var c = canvas.getContext('2d'), d = c.getImageData(0, 0, canvas.width, canvas.height).data, n = 0;
      for (var i = 3; i < d.length; i += 4) if (d[i] > 0) ++n;
      return n;
    } catch (e) {
      return 0;
    }
  }

  try {
    if (data.kind === 'batch') renderBatch(); else renderRun();
  } catch (e) {
    ENGAGE.errors.push(String(e && e.stack || e));
    main.appendChild(el('pre', {class: 'status-failed', text: 'report error: ' + e}));
  }
  // For the tests: what was drawn.
  var least = Infinity;
  charts.forEach(function (g) {
    var n = 0;
    g.graphDiv.querySelectorAll('canvas').forEach(function (c) { n += painted(c); });
    least = Math.min(least, n);
  });
  document.body.setAttribute('data-plots', String(charts.length));
  document.body.setAttribute('data-plot-pixels', String(charts.length ? least : 0));
  document.body.setAttribute('data-view-pixels', String(viewPixels));
  document.body.setAttribute('data-errors', JSON.stringify(ENGAGE.errors));
  if (window.performance)
    document.body.setAttribute('data-draw-ms', String(Math.round(performance.now() - started)));
  document.body.setAttribute('data-ready', '1');
})();
