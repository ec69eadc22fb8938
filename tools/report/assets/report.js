// triadcal HTML report: builds the page from the OUT files embedded in
// <script id="triadcal-data"> (an array of {name, out}). Charts are drawn by
// uPlot (inlined before this script). After drawing, the page checks that
// every chart canvas holds coloured pixels inside its plotting area and that
// no script error occurred, and writes the result into #triadcal-status
// (data-status="ok" or "fail"), which the browser test reads.
(function () {
  'use strict';

  // Filled from the page's first script (html_report.cpp): script errors and
  // console.error / console.warn calls, wherever they come from.
  var errors = window.triadcalErrors || [];

  // Saturated colours only: the self-check tells a drawn series from the grey
  // grid and axes by its saturation.
  var PALETTE = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#e377c2', '#17becf',
                 '#bcbd22', '#0b3d91', '#b8860b'];
  var charts = [];  // {title, plot}

  // ---------------------------------------------------------------- helpers
  function el(tag, attrs, children) {
    var e = document.createElement(tag);
    if (attrs) {
      Object.keys(attrs).forEach(function (k) {
        if (k === 'text') e.textContent = attrs[k];
        else if (k === 'cls') e.className = attrs[k];
        else e.setAttribute(k, attrs[k]);
      });
    }
    (children || []).forEach(function (c) {
      if (c === null || c === undefined) return;
      e.appendChild(typeof c === 'string' ? document.createTextNode(c) : c);
    });
    return e;
  }
  function isNum(x) { return typeof x === 'number' && isFinite(x); }
  function has(o, k) { return o && Object.prototype.hasOwnProperty.call(o, k); }
  function g(x, digits) {  // like printf %.<digits>g
    if (!isNum(x)) return x === null || x === undefined ? '-' : String(x);
    return Number(x.toPrecision(digits || 4)).toString();
  }

  // The value to the digit of its sigma (two significant digits of sigma);
  // the same rule as tools/report/value_format.cpp.
  function fixedNoMinusZero(x, d) {
    var s = x.toFixed(d);
    if (/^-[0.]*$/.test(s)) s = s.slice(1);
    return s;
  }
  function fmt(value, sigma) {
    if (!isNum(value)) return {value: String(value), sigma: '-'};
    if (!isNum(sigma) || !(sigma > 0)) return {value: g(value, 6), sigma: '-'};
    var lead = Math.floor(Math.log10(sigma));
    var unit = Math.pow(10, lead - 1);
    if (Math.round(sigma / unit) >= 100) { lead += 1; unit *= 10; }
    var dec = 1 - lead;
    if (dec > 8 || lead > 9) {
      var vl = value !== 0 ? Math.floor(Math.log10(Math.abs(value))) : lead;
      return {value: value.toExponential(Math.max(0, vl - lead + 1)), sigma: sigma.toExponential(1)};
    }
    if (dec >= 0) return {value: fixedNoMinusZero(value, dec), sigma: fixedNoMinusZero(sigma, dec)};
    return {value: fixedNoMinusZero(Math.round(value / unit) * unit, 0),
            sigma: fixedNoMinusZero(Math.round(sigma / unit) * unit, 0)};
  }
  // An estimate, or the prior's value of a held / not estimable parameter.
  function pe(q) {
    return q.estimable === false ? g(q.value, 6) + ' (not estimated)' : pm(q.value, q.sigma);
  }
  function pm(value, sigma) {
    var f = fmt(value, sigma);
    return f.sigma === '-' ? f.value : f.value + ' \u00b1 ' + f.sigma;
  }

  function section(parent, title, note) {
    var s = el('section', null, [el('h2', {text: title})]);
    if (note) s.appendChild(el('p', {cls: 'note', text: note}));
    parent.appendChild(s);
    return s;
  }
  function table(head, rows, cls) {
    var t = el('table', {cls: cls || 'data'});
    t.appendChild(el('thead', null, [el('tr', null, head.map(function (h) {
      return el('th', {text: h});
    }))]));
    var body = el('tbody');
    rows.forEach(function (r) {
      var tr = el('tr');
      r.forEach(function (c) {
        if (c instanceof Node) tr.appendChild(el('td', null, [c]));
        else tr.appendChild(el('td', {text: c === undefined || c === null ? '-' : String(c)}));
      });
      body.appendChild(tr);
    });
    t.appendChild(body);
    return t;
  }
  function badge(state, text) {
    return el('span', {cls: 'badge ' + state, text: text});
  }

  // --------------------------------------------------------------- charts
  function chartWidth(parent) {
    return Math.max(480, Math.min(1100, (parent.clientWidth || 900) - 20));
  }
  // Vertical dashed lines at given x values (bench frequencies), labelled.
  function markersPlugin(marks) {
    return {hooks: {draw: [function (u) {
      var ctx = u.ctx;
      ctx.save();
      ctx.strokeStyle = '#444';
      ctx.fillStyle = '#444';
      ctx.setLineDash([4, 4]);
      ctx.lineWidth = 1;
      ctx.font = Math.round(11 * devicePixelRatio) + 'px sans-serif';
      marks.forEach(function (m) {
        var x = Math.round(u.valToPos(m.x, 'x', true));
        if (x < u.bbox.left || x > u.bbox.left + u.bbox.width) return;
        ctx.beginPath();
        ctx.moveTo(x, u.bbox.top);
        ctx.lineTo(x, u.bbox.top + u.bbox.height);
        ctx.stroke();
        ctx.fillText(m.label, x + 3, u.bbox.top + 12 * devicePixelRatio);
      });
      ctx.restore();
    }]}};
  }
  // Tick labels readable at any magnitude (uPlot's default rounds 1e-4 to 0).
  function ticks(u, splits) {
    return splits.map(function (v) {
      if (v === null || v === undefined) return '';
      var a = Math.abs(v);
      if (a !== 0 && (a < 1e-3 || a >= 1e6)) return v.toExponential(0);
      return Number(v.toPrecision(6)).toLocaleString('en-US', {maximumFractionDigits: 6});
    });
  }
  // opts: {title, xLabel, yLabel, xLog, yLog, series: [{label, values, dash, points}],
  //        x: [...], marks: [{x, label}], bars}
  function chart(parent, o) {
    var box = el('div', {cls: 'chart'});
    parent.appendChild(box);
    var series = [{label: o.xLabel}];
    var data = [o.x];
    o.series.forEach(function (s, i) {
      var sd = {label: s.label, stroke: s.color || PALETTE[i % PALETTE.length], width: 1.5,
                spanGaps: false};
      if (s.dash) sd.dash = s.dash;
      if (s.points) {
        sd.points = {show: true, size: 7, fill: sd.stroke};
        sd.paths = function () { return null; };
      } else {
        sd.points = {show: false};
      }
      series.push(sd);
      data.push(s.values);
    });
    var opts = {
      title: o.title,
      width: chartWidth(parent),
      height: o.height || 300,
      series: series,
      scales: {x: {time: false, distr: o.xLog ? 3 : 1}, y: {distr: o.yLog ? 3 : 1}},
      axes: [{label: o.xLabel, values: ticks}, {label: o.yLabel, size: 70, values: ticks}],
      legend: {show: true},
      plugins: o.marks && o.marks.length ? [markersPlugin(o.marks)] : [],
    };
    if (o.xRange) opts.scales.x.range = function () { return o.xRange; };
    var plot = new uPlot(opts, data, box);
    charts.push({title: o.title, plot: plot});
    return plot;
  }

  // Correlation heat map: a table whose cells are coloured by r (blue -1,
  // white 0, red +1); the value is in each cell's tooltip.
  function heatmap(parent, names, matrix) {
    var t = el('table', {cls: 'heat'});
    var hr = el('tr', null, [el('th')]);
    names.forEach(function (n) { hr.appendChild(el('th', {cls: 'rot'}, [el('div', {text: n})])); });
    t.appendChild(hr);
    matrix.forEach(function (row, i) {
      var tr = el('tr', null, [el('th', {text: names[i]})]);
      row.forEach(function (r, j) {
        var a = Math.min(1, Math.abs(r));
        var c = r >= 0 ? 'rgba(214,39,40,' + a.toFixed(3) + ')' : 'rgba(31,119,180,' + a.toFixed(3) + ')';
        tr.appendChild(el('td', {style: 'background:' + c,
                                 title: names[i] + ' / ' + names[j] + ': r = ' + g(r, 3),
                                 text: i !== j && Math.abs(r) >= 0.5 ? g(r, 1) : ''}));
      });
      t.appendChild(tr);
    });
    parent.appendChild(el('div', {cls: 'heatwrap'}, [t]));
  }

  // ---------------------------------------------------------- shared parts
  // SPEC section 3 order, then the gyro's (section 10); effect parameters
  // ("effect.param") after, as given.
  var GYRO = 'gyro.';
  var ORDER = ['Kx', 'Ky', 'Kz', 'W0x', 'W0y', 'W0z', 'alpha_x', 'alpha_y', 'beta_x', 'beta_z',
               'gamma_y', 'gamma_z', 'Kxx', 'Kxy', 'Kxz', 'Kyx', 'Kyy', 'Kyz', 'Kzx', 'Kzy', 'Kzz',
               'dpsi', 'dtheta_c', 'dlambda2', 'dx2', 'dy2', 'dz2'].concat(
      ['Kx', 'Ky', 'Kz', 'W0x', 'W0y', 'W0z', 'alpha_x', 'alpha_y', 'beta_x', 'beta_z', 'gamma_y',
       'gamma_z', 'Gxx', 'Gxy', 'Gxz', 'Gyx', 'Gyy', 'Gyz', 'Gzx', 'Gzy', 'Gzz'].map(function (n) {
        return GYRO + n;
      }));
  function isGyro(name) { return name.indexOf(GYRO) === 0; }
  // The parameters whose name passes keep(name), or null when none does.
  function pick(params, keep) {
    var o = null;
    Object.keys(params || {}).forEach(function (n) {
      if (keep(n)) { o = o || {}; o[n] = params[n]; }
    });
    return o;
  }
  function ordered(names) {
    var known = ORDER.filter(function (n) { return names.indexOf(n) >= 0; });
    return known.concat(names.filter(function (n) { return ORDER.indexOf(n) < 0; }));
  }
  function keys(o) { return ordered(Object.keys(o || {})); }
  function paramRows(params, extra) {
    return keys(params).map(function (name) {
      var p = params[name];
      // Not estimable (held, or not separable): the value is the prior's and
      // its sigma no estimate.
      var f = p.estimable === false ? {value: g(p.value, 6), sigma: '-'} : fmt(p.value, p.sigma);
      var flags = [];
      if (p.estimable === false) flags.push('not estimable: prior value');
      if (extra) flags = flags.concat(extra(name, p));
      return [name, f.value, f.sigma, p.unit || '', flags.join('; ')];
    });
  }
  function paramTable(parent, params, extra, caption, sigmaMethod) {
    if (!params) return;
    var note = 'Each value is printed to the digit of its sigma (two significant digits of sigma).';
    if (sigmaMethod === 'hac') {
      note += ' The residuals are correlated in time, so sigma is the HAC (sandwich) one, ' +
              'never below the white-noise sigma.';
    }
    var s = section(parent, caption || 'Parameters', note);
    s.appendChild(table(['parameter', 'value', 'sigma', 'unit', 'note'], paramRows(params, extra)));
  }
  function fitFlags(out) {
    var held = out.held || [];
    var bound = out.at_prior_bound || [];
    return function (name) {
      var f = [];
      if (held.indexOf(name) >= 0) f.push('held at nominal');
      if (bound.indexOf(name) >= 0) f.push('beyond 3 prior sigma');
      return f;
    };
  }
  function marksFor(freqs) {
    var m = [];
    var f1 = freqs && freqs[0], f2 = freqs && freqs[1];
    if (isNum(f1) && f1 > 0) { m.push({x: f1, label: 'f1'}); m.push({x: 2 * f1, label: '2f1'}); }
    if (isNum(f2) && f2 > 0) { m.push({x: f2, label: 'f2'}); m.push({x: 2 * f2, label: '2f2'}); }
    if (isNum(f1) && isNum(f2) && f1 > 0 && f2 > 0) m.push({x: f1 + f2, label: 'f1+f2'});
    return m;
  }
  // heading: the section's title (default "Residual" and the label).
  function residualCharts(parent, rp, label, heading) {
    if (!rp || !rp.t_s || !rp.channels) return;
    var s = section(parent, heading || 'Residual' + (label ? ' ' + label : ''),
                    rp.what + ' [' + rp.unit + ']; decimation: ' + rp.decimation + '.');
    chart(s, {title: 'Residual time series' + (label ? ' (' + label + ')' : ''),
              xLabel: 't [s]', yLabel: rp.unit, x: rp.t_s,
              series: rp.channels.map(function (c) {
                return {label: c.name + ' (RMS ' + g(c.rms, 3) + ')', values: c.values};
              })});
    var sp = rp.spectrum;
    if (sp && sp.freq_hz && sp.freq_hz.length > 1) {
      chart(s, {title: 'Residual spectrum' + (label ? ' (' + label + ')' : '') +
                       ', bench frequencies marked',
                xLabel: 'frequency [Hz]', yLabel: 'power [' + rp.unit + '\u00b2]',
                xLog: true, yLog: true,
                x: sp.freq_hz,
                marks: marksFor(rp.bench_frequencies_hz),
                series: sp.channels.map(function (c) {
                  return {label: c.name, values: c.power.map(function (v) { return v > 0 ? v : null; })};
                })});
      s.appendChild(el('p', {cls: 'note', text: 'Bench frequencies found in the angles: f1 = ' +
          g(rp.bench_frequencies_hz[0], 4) + ' Hz, f2 = ' + g(rp.bench_frequencies_hz[1], 4) +
          ' Hz. Spectrum decimation: ' + sp.decimation + '.'}));
    }
  }
  // noiseConsistent: the verdict's noise_consistent (false: the residual
  // holds another noise than the declared one, whatever its structure).
  // cleanNote: what to say when neither (default: consistent with the
  // declared noise).
  function residualStats(parent, ra, title, noiseConsistent, cleanNote) {
    if (!ra || !ra.channels) return;
    var s = section(parent, title || 'Residual statistics',
                    ra.structure ? 'STRUCTURE: ' + ra.structure_summary :
                    noiseConsistent === false ?
                        'No structure found in the residual, but its noise is NOT the declared ' +
                        'one (the verdict gives both figures).' :
                        cleanNote || 'The residual is consistent with the declared noise.');
    s.appendChild(table(['channel', 'RMS', 'unit', 'Ljung-Box p', 'lag-1 autocorr.', 'strongest peak'],
        ra.channels.map(function (c) {
          var pk = c.spectrum_peaks && c.spectrum_peaks.length ?
              g(c.spectrum_peaks[0].freq_hz, 4) + ' Hz, ' +
              g(100 * c.spectrum_peaks[0].power_fraction, 2) + ' % of the variance' +
              (c.spectrum_peaks[0].bench_combination ? ' (' + c.spectrum_peaks[0].bench_combination + ')' : '') : '';
          return [c.channel, g(c.rms, 4), c.unit, g(c.ljung_box_p, 3), g(c.lag1_autocorrelation, 3), pk];
        })));
  }
  function correlationSection(parent, corr, note) {
    if (!corr || !corr.names || !corr.matrix) return;
    var s = section(parent, 'Correlation of the estimates',
                    note || 'Red positive, blue negative; |r| >= 0.5 written in the cell.');
    heatmap(s, corr.names, corr.matrix);
  }

  // ---------------------------------------------------------- verdicts
  // {state: pass|fail|info, label, reasons[]} from what the OUT says.
  function judge(out) {
    var r = [];
    switch (out.command) {
      case 'fit':
        if (out.converged === false) r.push('the solver did not converge');
        if (out.residual_analysis && out.residual_analysis.structure) {
          r.push('residual not consistent with the declared noise: ' +
                 out.residual_analysis.structure_summary);
        }
        if (out.unobservable && out.unobservable.length) r.push('some parameters are not separable');
        if (out.verdict && out.verdict.noise_consistent === false) {
          r.push('the reading noise in the residuals is not the declared one');
        }
        var gv = out.gyro && out.gyro.verdict;
        if (gv && gv.pass === false) r.push(gv.sentence);  // it names the gyro
        return {state: r.length ? 'fail' : 'pass', reasons: r};
      case 'batch':
        if (out.fail) r.push(out.fail + ' unit(s) outside their limits');
        if (out.error) r.push(out.error + ' unit(s) could not be calibrated');
        return {state: r.length ? 'fail' : 'pass', reasons: r};
      case 'diagnose':
        if (out.unexplained_structure) r.push('structure remains that no candidate explains');
        return {state: r.length ? 'fail' : 'pass', reasons: r};
      case 'filter':
        if (out.innovations && isNum(out.innovations.mean_nis) && out.settings && out.settings.epochs) {
          var sd = Math.sqrt(12 / out.settings.epochs);
          if (Math.abs(out.innovations.mean_nis - 6) > 4 * sd) {
            r.push('mean NIS ' + g(out.innovations.mean_nis, 3) + ' is more than 4 sd from 6');
          }
          return {state: r.length ? 'fail' : 'pass', reasons: r};
        }
        return {state: 'info', reasons: r};
      case 'observability':
        if (out.unobservable && out.unobservable.length) r.push('unobservable directions remain');
        return {state: r.length ? 'fail' : 'pass', reasons: r};
      case 'montecarlo':
        Object.keys(out.scatter_over_crb || {}).forEach(function (k) {
          if (out.scatter_over_crb[k].within_tolerance === false) {
            r.push(k + ': scatter/CRB outside tolerance');
          }
        });
        return {state: r.length ? 'fail' : 'pass', reasons: r};
      case 'design':
        (out.targets || []).forEach(function (t) {
          if (!t.reached) r.push('target sigma(' + t.target + ') not reached');
        });
        return {state: r.length ? 'fail' : 'pass', reasons: r};
      default:
        return {state: 'info', reasons: r};
    }
  }
  // The verdict sentence: a string, or (fit, diagnose, joint fit) an object
  // whose `sentence` says it.
  function sentenceOf(v) {
    if (!v) return '';
    if (typeof v === 'string') return v;
    if (typeof v.sentence === 'string') return v.sentence;
    return '';
  }
  function verdictText(out) {
    return sentenceOf(out.verdict) || sentenceOf(out.batch && out.batch.verdict);
  }
  function header(parent, item) {
    var out = item.out;
    var j = judge(out);
    var label = j.state === 'pass' ? 'PASS' : j.state === 'fail' ? 'CHECK' : 'INFO';
    var h = el('header', {cls: 'verdict ' + j.state}, [
      el('h1', null, [badge(j.state, label), ' triadcal ' + out.command + ': ' + item.name]),
      el('p', {cls: 'verdict-text', text: verdictText(out)})]);
    if (j.reasons.length) h.appendChild(el('ul', null, j.reasons.map(function (x) { return el('li', {text: x}); })));
    var facts = [];
    if (out.run) facts.push('run: ' + (typeof out.run === 'string' ? out.run : JSON.stringify(out.run)));
    if (out.input) facts.push('input: ' + out.input);
    if (out.scenario) facts.push('scenario: ' + out.scenario);
    if (isNum(out.samples)) facts.push(out.samples + ' samples');
    if (isNum(out.chi2_per_dof)) facts.push('chi2/dof ' + g(out.chi2_per_dof, 4) + ' (1 expected)');
    // Several runs together calibrate the accelerometer triad only.
    var gn = out.gyro_not_calibrated;
    if (gn && gn.runs && gn.runs.length) {
      facts.push('gyro not calibrated here (runs ' + gn.runs.join(', ') + '): ' + gn.reason);
    }
    var pv = out.provenance || {};
    if (pv.sensor && pv.sensor.serial) facts.push('sensor ' + pv.sensor.serial);
    if (pv.sensor && pv.sensor.model) facts.push('model ' + pv.sensor.model);
    if (pv.date_utc) facts.push('made ' + pv.date_utc);
    if (pv.version) facts.push('triadcal ' + pv.version + (pv.git_commit ? ' (' + pv.git_commit + ')' : ''));
    if (facts.length) h.appendChild(el('p', {cls: 'facts', text: facts.join(' \u00b7 ')}));
    parent.appendChild(h);
    return j;
  }

  // ------------------------------------------------------ per command
  function renderFit(p, out) {
    var gyro = out.gyro && out.gyro.verdict ? out.gyro : null;
    // With the gyro, its parameters are shown in its own section.
    var accel = gyro ? pick(out.parameters, function (n) { return !isGyro(n); }) : out.parameters;
    paramTable(p, accel, fitFlags(out), null, out.sigma_method);
    residualCharts(p, out.residual_plot);
    residualStats(p, out.residual_analysis, null, (out.verdict || {}).noise_consistent);
    if (gyro) renderGyro(p, out, gyro);
    correlationSection(p, out.correlation);
  }
  // The gyro triad (SPEC section 10): its verdict, parameters, rate noise,
  // and its increment residual with spectrum and statistics.
  function renderGyro(p, out, gyro) {
    var v = gyro.verdict;
    var state = v.pass ? 'pass' : 'fail';
    var s = section(p, 'Gyro triad');
    s.appendChild(el('p', {cls: 'verdict-text'},
                      [badge(state, v.pass ? 'PASS' : 'CHECK'), ' ' + v.sentence]));
    var n = gyro.noise;
    if (n && n.estimated_dps) {
      var axes = ['x', 'y', 'z'];
      s.appendChild(table(['channel', 'rate noise estimated', 'declared', 'unit'],
          axes.map(function (a, i) {
            return ['g' + a, g(n.estimated_dps[i], 3),
                    n.declared_dps ? g(n.declared_dps[i], 3) : '-', n.unit];
          })));
    }
    paramTable(p, pick(out.parameters, isGyro), fitFlags(out), 'Gyro parameters',
               out.sigma_method);
    residualCharts(p, gyro.residual_plot, 'gyro', 'Gyro residual');
    residualStats(p, gyro.residual_analysis, 'Gyro residual statistics', undefined,
                  'No structure found in the gyro residual.');
  }
  function renderDiagnose(p, out) {
    var s = section(p, 'Candidate effects (round 1)', out.selection_rule);
    s.appendChild(table(['effect', 'statistic', 'dof', 'p-value', 'Wald p-value', 'threshold',
                         'selected', 'note'],
        (out.ranking || []).map(function (t) {
          return [t.effect, g(t.statistic, 4), t.dof, g(t.p_value, 3),
                  t.refit && isNum(t.wald_p_value) ? g(t.wald_p_value, 3) : '',
                  g(t.threshold, 3), t.selected ? 'yes' : '', t.note || ''];
        })));
    var hide = [];
    var selected = out.selected || [];
    (out.ranking || []).forEach(function (t) {
      if (t.note && !t.selected && selected.indexOf(t.effect) < 0) hide.push(t.effect + ': ' + t.note);
    });
    // What the loop's final fit could not see (could_hide): the smallest size
    // of each effect not selected that the run would detect, and how far an
    // effect of that size would move the estimates unseen.
    (out.could_hide || []).forEach(function (h) {
      if (h.undetectable || !isNum(h.minimal_detectable)) {
        hide.push(h.effect + ': ' + (h.note || 'this run cannot detect it'));
      } else {
        hide.push(h.effect + ': up to ' + g(h.minimal_detectable, 3) + ' ' + (h.unit || '') +
                  ' would go undetected (power ' + g(h.power, 2) + ' at alpha ' + g(h.alpha, 2) +
                  '), moving ' + (h.parameter || 'the estimates') + ' by up to ' +
                  g(h.max_shift_sigma, 3) + ' sigma');
      }
    });
    // The last round's candidates with some evidence (p < 0.05) that did not
    // pass the selection threshold: present perhaps, too weak to add.
    var tests = out.tests || [];
    var last = tests.reduce(function (m, t) { return Math.max(m, t.round || 0); }, 0);
    tests.forEach(function (t) {
      if (t.round === last && !t.selected && isNum(t.p_value) && t.p_value < 0.05) {
        hide.push(t.effect + ': some evidence in round ' + t.round + ' (p = ' + g(t.p_value, 2) +
                  ', threshold ' + g(t.threshold, 2) + '), not selected');
      }
    });
    var heldAfter = (out.after || {}).held || [];
    if (heldAfter.length) {
      hide.push('held at nominal (the run cannot determine them; an error there moves into the ' +
                'other parameters): ' + heldAfter.join(', '));
    }
    (out.notes || []).forEach(function (n) { hide.push(n); });
    if (out.after && out.after.residual && out.after.residual.structure) {
      hide.push('remaining structure: ' + out.after.residual.structure_summary);
    }
    var hs = section(p, 'What could hide',
        'Effects this run could not test or tell apart, near-misses of the last round, and ' +
        'parameters held at nominal: they may remain in the estimates.');
    if (hide.length) hs.appendChild(el('ul', null, hide.map(function (x) { return el('li', {text: x}); })));
    else hs.appendChild(el('p', {text: 'Every candidate was tested, none came near the threshold ' +
                                         'in the last round, and no parameter is held.'}));

    var b = out.before || {}, a = out.after || {};
    var ba = section(p, 'Before and after', 'effects after: ' + ((a.effects || []).join(', ') || 'none'));
    var rows = [['chi2/dof', g(b.chi2_per_dof, 4), g(a.chi2_per_dof, 4)]];
    Object.keys(b.residual_rms || {}).forEach(function (k) {
      rows.push([k + ' RMS', g(b.residual_rms[k], 4), g((a.residual_rms || {})[k], 4)]);
      rows.push([k + ' Ljung-Box p', g((b.whiteness_p || {})[k], 3), g((a.whiteness_p || {})[k], 3)]);
    });
    if (isNum(b.error_vs_truth_rms_sigma)) {
      rows.push(['error vs truth, RMS in sigma', g(b.error_vs_truth_rms_sigma, 3),
                 g(a.error_vs_truth_rms_sigma, 3)]);
    }
    ba.appendChild(table(['quantity', 'before', 'after'], rows));
    var names = keys(a.parameters);
    ba.appendChild(table(['parameter', 'before', 'after', 'unit', 'err/sigma before', 'err/sigma after'],
        names.map(function (n) {
          var pb = (b.parameters || {})[n], pa = a.parameters[n];
          var eb = b.error_vs_truth && b.error_vs_truth[n], ea = a.error_vs_truth && a.error_vs_truth[n];
          return [n, pb ? pe(pb) : 'new', pe(pa), pa.unit,
                  eb ? g(eb.error_in_sigma, 3) : '-', ea ? g(ea.error_in_sigma, 3) : '-'];
        })));
    residualCharts(p, b.residual_plot, 'before');
    residualCharts(p, a.residual_plot, 'after');
    residualStats(p, a.residual, 'Residual statistics after');
    if (a.gyro && a.gyro.verdict) renderGyroBeforeAfter(p, b.gyro, a.gyro);
  }
  // With a gyro (SPEC section 10), every fit of the loop estimated it: its
  // verdict before and after, and its increment residual before and after
  // (its parameters are in the table above).
  function renderGyroBeforeAfter(p, before, after) {
    var s = section(p, 'Gyro triad, before and after');
    [['before', before], ['after', after]].forEach(function (st) {
      var v = st[1] && st[1].verdict;
      if (!v) return;
      s.appendChild(el('p', {cls: 'verdict-text'},
                        [badge(v.pass ? 'pass' : 'fail', v.pass ? 'PASS' : 'CHECK'),
                         ' ' + st[0] + ': ' + v.sentence]));
    });
    residualCharts(p, before && before.residual_plot, 'gyro, before', 'Gyro residual before');
    residualCharts(p, after.residual_plot, 'gyro, after', 'Gyro residual after');
  }
  function renderFilter(p, out) {
    ['ekf', 'rts'].forEach(function (k) {
      if (out[k]) paramTable(p, out[k].parameters, null, 'Parameters: ' + k.toUpperCase());
    });
    if (out.innovations) {
      var s = section(p, 'Innovations');
      s.appendChild(table(['quantity', 'value'], Object.keys(out.innovations).map(function (k) {
        var v = out.innovations[k];
        return [k, Array.isArray(v) ? v.map(function (x) { return g(x, 3); }).join(', ') : g(v, 4)];
      })));
    }
  }
  function renderCompare(p, out) {
    var names = keys((out.batch || {}).parameters);
    var s = section(p, 'EKF, RTS and batch', 'Differences in units of the batch sigma.');
    s.appendChild(table(['parameter', 'EKF', 'RTS', 'batch', 'unit', 'RTS-EKF', 'batch-RTS'],
        names.map(function (n) {
          var e = out.ekf.parameters[n], r = out.rts.parameters[n], b = out.batch.parameters[n];
          var d = (out.differences_in_sigma || {})[n] || {};
          return [n, pm(e.value, e.sigma), pm(r.value, r.sigma), pm(b.value, b.sigma), b.unit,
                  g(d.rts_minus_ekf, 3), g(d.batch_minus_rts, 3)];
        })));
    chart(s, {title: 'Differences between estimators [batch sigma]', xLabel: 'parameter index',
              yLabel: 'sigma', x: names.map(function (_, i) { return i; }),
              series: [{label: 'RTS - EKF', points: true, values: names.map(function (n) {
                         return (out.differences_in_sigma[n] || {}).rts_minus_ekf; })},
                       {label: 'batch - RTS', points: true, values: names.map(function (n) {
                         return (out.differences_in_sigma[n] || {}).batch_minus_rts; })}]});
    s.appendChild(el('p', {cls: 'note', text: 'Parameter index: ' + names.map(function (n, i) {
      return i + ' ' + n; }).join(', ')}));
  }
  function renderObservability(p, out) {
    var names = keys(out.crb);
    var w = (out.with_constraints || {}).crb || out.crb, wo = (out.without_constraints || {}).crb || {};
    var prior = out.prior_sigma || {};
    var s = section(p, 'Cramer-Rao sigma', 'With and without the constraints (' +
                    (out.constraints || []).join(', ') + '); the prior sigma for scale.');
    s.appendChild(table(['parameter', 'CRB with', 'CRB without', 'prior sigma', 'unit', 'with / prior'],
        names.map(function (n) {
          return [n, g(w[n], 3), g(wo[n], 3), g(prior[n], 3), (out.units || {})[n] || '',
                  g(w[n] / prior[n], 3)];
        })));
    chart(s, {title: 'Cramer-Rao sigma over the prior sigma (log)', xLabel: 'parameter index',
              yLabel: 'sigma / prior', yLog: true, x: names.map(function (_, i) { return i; }),
              series: [{label: 'with constraints', points: true,
                        values: names.map(function (n) { return w[n] / prior[n]; })},
                       {label: 'without constraints', points: true,
                        values: names.map(function (n) { return has(wo, n) ? wo[n] / prior[n] : null; })}]});
    s.appendChild(el('p', {cls: 'note', text: 'Parameter index: ' + names.map(function (n, i) {
      return i + ' ' + n; }).join(', ')}));
    var dirs = [];
    ['unobservable', 'weakly_observable'].forEach(function (k) {
      (out[k] || []).forEach(function (d) { dirs.push(k + ': ' + (d.description || JSON.stringify(d))); });
    });
    ((out.without_constraints || {}).unobservable || []).forEach(function (d) {
      dirs.push('without the constraints, unobservable: ' + (d.description || JSON.stringify(d)));
    });
    var ds = section(p, 'Unobservable directions');
    ds.appendChild(dirs.length ? el('ul', null, dirs.map(function (x) { return el('li', {text: x}); }))
                               : el('p', {text: 'none'}));
    correlationSection(p, out.correlation);
  }
  function renderDesign(p, out) {
    var d = out.duration;
    if (d && d.durations_s && d.quasi_harmonic && d.groups) {
      var st = (out.settings || {});
      var s = section(p, 'Sigma against run duration',
          'Cramer-Rao sigma, log-log, per group: solid the worst member, dashed the best; ' +
          'quasi-harmonic profile against the static ' + d.static_positions + '-position method. ' +
          'Missing points: the method does not determine a member at that duration.');
      // Worst / best of a group's members at each duration; null when a
      // member is not determined (its sigma is the prior's).
      var pick = function (m, members, worst) {
        return d.durations_s.map(function (_, k) {
          var v = null;
          for (var i = 0; i < members.length; ++i) {
            var x = ((m.sigma || {})[members[i]] || [])[k];
            if (!isNum(x)) return null;
            v = v === null ? x : worst ? Math.max(v, x) : Math.min(v, x);
          }
          return v;
        });
      };
      d.groups.forEach(function (grp) {
        var series = [
          {label: 'quasi-harmonic, worst', color: PALETTE[0], values: pick(d.quasi_harmonic, grp.members, true)},
          {label: 'quasi-harmonic, best', color: PALETTE[0], dash: [6, 4], values: pick(d.quasi_harmonic, grp.members, false)}];
        if (d.static) {
          series.push({label: 'static, worst', color: PALETTE[1], values: pick(d.static, grp.members, true)});
          series.push({label: 'static, best', color: PALETTE[1], dash: [6, 4], values: pick(d.static, grp.members, false)});
        }
        var marks = [];
        if (isNum(st.design_duration_s)) marks.push({x: st.design_duration_s, label: 'design'});
        if (isNum(st.static_duration_s)) marks.push({x: st.static_duration_s, label: 'static'});
        chart(s, {title: grp.label + ' (' + grp.members.join(', ') + ')', xLabel: 'run duration [s]',
                  yLabel: 'sigma [' + grp.unit + ']', xLog: true, yLog: true, x: d.durations_s,
                  marks: marks, series: series, height: 260});
      });
    }
    if (out.targets && out.targets.length) {
      var ts = section(p, 'Targets');
      ts.appendChild(table(['target', 'sigma', 'unit', 'reached', 'after [s]'], out.targets.map(function (t) {
        return [t.target, g(t.sigma, 3), t.unit, t.reached ? 'yes' : 'NO', g(t.duration_s, 3)];
      })));
    }
    var c = out.comparison;
    if (c && c.rows) {
      var cs = section(p, 'Quasi-harmonic against the static method',
                       'quasi-harmonic ' + g(c.quasi_harmonic_duration_s, 4) + ' s');
      cs.appendChild(table(['parameter', 'quasi-harmonic', 'static', 'static, same duration', 'unit', 'static / q-h'],
          keys(c.rows).map(function (n) {
            var r = c.rows[n];
            return [n, g(r.quasi_harmonic, 3), g(r.static, 3), g(r.static_same_duration, 3), r.unit,
                    g(r.ratio_static_over_quasi_harmonic, 3)];
          })));
    }
    if (out.profiles && out.profiles.length) {
      var ps = section(p, 'Profiles');
      var pn = keys(out.profiles[0].sigma);
      ps.appendChild(table(['periods [s]', 'amplitudes [deg]'].concat(pn), out.profiles.map(function (q) {
        return [q.period_s.join(':'), q.amplitude_deg.join(':')].concat(pn.map(function (n) {
          return g(q.sigma[n], 2);
        }));
      }), 'data small'));
    }
  }
  function renderMonteCarlo(p, out) {
    var names = keys(out.parameters);
    var est = out.estimators || [];
    var s = section(p, 'Error scatter over the Cramer-Rao bound',
                    out.runs + ' runs; relative sampling error of a scatter ' +
                    g(out.sampling_error_relative, 2) + '.');
    chart(s, {title: 'scatter / CRB per parameter (1 is efficient)', xLabel: 'parameter index',
              yLabel: 'scatter / CRB', x: names.map(function (_, i) { return i; }),
              series: est.map(function (e) {
                return {label: e, points: true, values: names.map(function (n) {
                  var q = out.parameters[n][e];
                  return q && isNum(q.scatter_over_crb) ? q.scatter_over_crb : null;
                })};
              })});
    s.appendChild(el('p', {cls: 'note', text: 'Parameter index: ' + names.map(function (n, i) {
      return i + ' ' + n; }).join(', ')}));
    s.appendChild(table(['parameter', 'CRB'].concat(est.map(function (e) { return e + ' scatter/CRB'; }))
        .concat(est.map(function (e) { return e + ' bias/CRB'; })),
        names.map(function (n) {
          var q = out.parameters[n];
          return [n, g(q.crb, 3)].concat(est.map(function (e) { return g((q[e] || {}).scatter_over_crb, 3); }))
              .concat(est.map(function (e) { return g((q[e] || {}).bias_over_crb, 3); }));
        })));
    if (out.pooled) {
      var ps = section(p, 'Pooled');
      ps.appendChild(table(['estimator', 'RMS normalised error', 'runs', 'failures'],
          Object.keys(out.pooled).map(function (e) {
            var q = out.pooled[e];
            return [e, g(q.rms_normalised_error, 4), q.runs, q.failures];
          })));
    }
  }
  function renderStatic(p, out) {
    paramTable(p, out.parameters);
    if (out.positions && out.positions.length) {
      var s = section(p, 'Static positions',
                      'Residual of each position after the fit (x, y, z and the error of |W| - 1 g)' +
                      (isNum(out.residual_rms_mg) ? '; RMS over positions ' + g(out.residual_rms_mg, 3) + ' mg.' : '.'));
      var pos = out.positions;
      var axis = function (c) {
        return pos.map(function (q) { return q.residual_mg && isNum(q.residual_mg[c]) ? q.residual_mg[c] : null; });
      };
      var series = [{label: 'x', points: true, values: axis(0)}, {label: 'y', points: true, values: axis(1)},
                    {label: 'z', points: true, values: axis(2)}];
      if (pos.some(function (q) { return isNum(q.norm_residual_mg); })) {
        series.push({label: '|W| - 1 g', points: true, values: pos.map(function (q) {
          return isNum(q.norm_residual_mg) ? q.norm_residual_mg : null; })});
      }
      chart(s, {title: 'Residual per position [mg]', xLabel: 'position index', yLabel: 'mg',
                x: pos.map(function (_, i) { return i; }), series: series, height: 260});
      s.appendChild(el('p', {cls: 'note', text: 'Position index: ' + pos.map(function (q, i) {
        return i + ' ' + q.name; }).join(', ')}));
      s.appendChild(table(['position', 'samples', 'duration [s]', 'mean [mV]', 'std [mV]', 'residual [mg]'],
          out.positions.map(function (q) {
            return [q.name, q.samples, g(q.duration_s, 4),
                    (q.mean_mV || []).map(function (x) { return g(x, 6); }).join(', '),
                    (q.std_mV || []).map(function (x) { return g(x, 3); }).join(', '),
                    (q.residual_mg || []).map(function (x) { return g(x, 3); }).join(', ')];
          })));
    }
  }
  // A batch summary: the counts, then one row per unit with what failed.
  function renderBatch(p, out) {
    var s = section(p, 'Units of ' + (out.manifest || 'the batch'),
                    (out.units || 0) + ' units: ' + (out.pass || 0) + ' pass, ' + (out.fail || 0) +
                    ' fail, ' + (out.error || 0) + ' error' +
                    (out.date ? ' (' + out.date + ')' : ''));
    s.appendChild(table(['serial', 'status', 'reason', 'limits exceeded', 'largest change',
                         'diagnose selected', 'time [s]'],
        (out.results || []).map(function (u) {
          var v = (u.violations || []).map(function (x) {
            return typeof x === 'string' ? x : x.text || (x.parameter || '') + ' ' + (x.limit || '');
          }).join('; ');
          var change = u.previous && isNum(u.largest_change_sigma) ?
              g(u.largest_change_sigma, 3) + ' sigma (' + u.largest_change_parameter + ')' : '';
          return [u.serial, badge(u.status === 'pass' ? 'pass' : 'fail', u.status.toUpperCase()),
                  u.reason || '', v, change, (u.diagnose_selected || []).join(', '),
                  isNum(u.time_s) ? g(u.time_s, 3) : ''];
        })));
  }
  function renderOne(parent, item) {
    var out = item.out;
    var art = el('article', {cls: 'out'});
    parent.appendChild(art);
    header(art, item);
    switch (out.command) {
      case 'fit': renderFit(art, out); break;
      case 'diagnose': renderDiagnose(art, out); break;
      case 'filter': renderFilter(art, out); break;
      case 'compare': renderCompare(art, out); break;
      case 'observability': renderObservability(art, out); break;
      case 'design': renderDesign(art, out); break;
      case 'montecarlo': renderMonteCarlo(art, out); break;
      case 'static': renderStatic(art, out); break;
      case 'batch': renderBatch(art, out); break;
      default:
        if (out.parameters) paramTable(art, out.parameters);
    }
  }

  // The parameters of an OUT, whatever the command ("parameters", or the
  // batch's / RTS's for compare and filter).
  function mainParameters(out) {
    // Only estimates: observability, design and montecarlo hold sigmas or
    // nominal values under their parameter keys.
    if (['observability', 'design', 'montecarlo'].indexOf(out.command) >= 0) return null;
    if (out.parameters) return out.parameters;
    if (out.batch && out.batch.parameters) return out.batch.parameters;
    if (out.rts && out.rts.parameters) return out.rts.parameters;
    return null;
  }
  function renderComparison(parent, items) {
    var withP = items.filter(function (it) { return mainParameters(it.out); });
    if (withP.length < 2) return;
    var names = [];
    withP.forEach(function (it) {
      Object.keys(mainParameters(it.out)).forEach(function (n) { if (names.indexOf(n) < 0) names.push(n); });
    });
    names = ordered(names);
    var s = section(parent, 'Per-run comparison',
        'Each run\'s estimate to the digit of its sigma; the last column is the largest ' +
        'difference from the runs\' weighted mean in units of the run\'s sigma; held or not ' +
        'estimable parameters (the prior\'s value) are left out of the mean.');
    var rows = [], dev = withP.map(function () { return []; });
    names.forEach(function (n, ni) {
      var ps = withP.map(function (it) { return mainParameters(it.out)[n]; });
      // Held or not estimable: the prior's value, not an estimate; left out.
      var est = function (q) { return q && q.estimable !== false && isNum(q.sigma) && q.sigma > 0; };
      var sw = 0, swx = 0;
      ps.forEach(function (q) {
        if (est(q)) { sw += 1 / (q.sigma * q.sigma); swx += q.value / (q.sigma * q.sigma); }
      });
      var mean = sw > 0 ? swx / sw : NaN;
      var worst = null;
      ps.forEach(function (q, k) {
        var z = est(q) && isNum(mean) ? (q.value - mean) / q.sigma : null;
        dev[k][ni] = z;
        if (z !== null && (worst === null || Math.abs(z) > Math.abs(worst))) worst = z;
      });
      var unit = (ps.filter(function (q) { return q; })[0] || {}).unit || '';
      rows.push([n].concat(ps.map(function (q) {
                     return !q ? '-' : est(q) ? pm(q.value, q.sigma) : g(q.value, 6) + ' (not estimated)';
                   }))
                   .concat([unit, g(worst, 3)]));
    });
    s.appendChild(table(['parameter'].concat(withP.map(function (it) { return it.name; }))
                        .concat(['unit', 'max |dev|/sigma']), rows));
    chart(s, {title: 'Deviation of each run from the weighted mean [own sigma]',
              xLabel: 'parameter index', yLabel: '(value - mean) / sigma',
              x: names.map(function (_, i) { return i; }),
              series: withP.map(function (it, k) { return {label: it.name, points: true, values: dev[k]}; })});
    s.appendChild(el('p', {cls: 'note', text: 'Parameter index: ' + names.map(function (n, i) {
      return i + ' ' + n; }).join(', ')}));
  }

  // ------------------------------------------------------ self-check
  // A chart has drawn when its plotting area holds at least 20 saturated
  // pixels (series colours; grid, axes and markers are grey).
  function drawnPixels(c) {
    var u = c.plot, b = u.bbox;
    var w = Math.max(1, Math.floor(b.width)), h = Math.max(1, Math.floor(b.height));
    var img = u.ctx.getImageData(Math.floor(b.left), Math.floor(b.top), w, h).data;
    var n = 0;
    for (var i = 0; i < img.length; i += 4) {
      if (img[i + 3] < 128) continue;
      var mx = Math.max(img[i], img[i + 1], img[i + 2]), mn = Math.min(img[i], img[i + 1], img[i + 2]);
      if (mx - mn > 60) n++;
    }
    return n;
  }
  function selfCheck() {
    var status = document.getElementById('triadcal-status');
    var blank = [];
    charts.forEach(function (c) {
      var n = 0;
      try { n = drawnPixels(c); } catch (e) { errors.push('self-check: ' + e.message); }
      c.plot.root.setAttribute('data-drawn-pixels', String(n));
      if (n < 20) blank.push(c.title);
    });
    var ok = errors.length === 0 && blank.length === 0;
    var result = {charts: charts.length, blank: blank, errors: errors};
    status.setAttribute('data-status', ok ? 'ok' : 'fail');
    status.setAttribute('data-result', JSON.stringify(result));
    status.textContent = ok ? 'self-check: ' + charts.length + ' charts drawn, no script error'
                            : 'self-check FAILED: ' + JSON.stringify(result);
  }

  // ------------------------------------------------------ main
  function main() {
    var root = document.getElementById('report');
    root.textContent = '';
    var items = JSON.parse(document.getElementById('triadcal-data').textContent);
    if (items.length > 1) {
      var sum = section(root, 'Summary of ' + items.length + ' outputs');
      sum.appendChild(table(['output', 'command', 'result', 'verdict'], items.map(function (it) {
        var j = judge(it.out);
        return [it.name, it.out.command,
                badge(j.state, j.state === 'pass' ? 'PASS' : j.state === 'fail' ? 'CHECK' : 'INFO'),
                verdictText(it.out)];
      })));
      renderComparison(root, items);
    }
    items.forEach(function (it) {
      try {
        renderOne(root, it);
      } catch (e) {
        errors.push(it.name + ': ' + e.message);
        root.appendChild(el('p', {cls: 'error', text: 'Could not draw ' + it.name + ': ' + e.message}));
      }
    });
    root.appendChild(el('footer', {text: 'Made by triadcal; charts by uPlot (MIT licence).'}));
  }
  try {
    main();
  } catch (e) {
    errors.push(e.message);
  }
  // uPlot draws in a microtask after construction; check once the page has loaded.
  if (document.readyState === 'complete') setTimeout(selfCheck, 0);
  else window.addEventListener('load', function () { setTimeout(selfCheck, 0); });
})();
