#include "protocols/report/report_page.h"

#include "core/util/markup_text.h"
#include "protocols/report/json_text.h"

namespace selfcal::report {
namespace {

constexpr const char* kStyle = R"css(
body { font-family: sans-serif; margin: 1.5em auto; max-width: 1300px; color: #222; }
h1 { margin-bottom: 0.2em; } h2 { border-bottom: 1px solid #ccc; margin-top: 1.6em; }
table { border-collapse: collapse; margin: 0.5em 0; } td, th { border: 1px solid #ddd; padding: 3px 8px; }
th { background: #f4f4f4; text-align: left; } td.num, span.num { font-variant-numeric: tabular-nums; }
.accepted { color: #1a7f37; } .refused { color: #b42318; }
.views { display: flex; gap: 12px; } .view { flex: 1; } .view canvas { width: 100%; border: 1px solid #ccc; }
.plots { display: flex; flex-wrap: wrap; gap: 16px; } .plot { width: 620px; }
#problems { color: #b42318; } pre { white-space: pre-wrap; font-size: 12px; }
)css";

// Draws from the data block: the two 3D views sharing one camera, the plots, the tables.
constexpr const char* kScript = R"js(
(function () {
  'use strict';
  const data = JSON.parse(document.getElementById('selfcal-data').textContent);
  const decode = function (base64, Type) {
    const text = atob(base64);
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; ++i) bytes[i] = text.charCodeAt(i);
    return new Type(bytes.buffer);
  };
  const num = function (key, value, scale, decimals) {
    if (value === null || value === undefined) return '<td class="num">&infin;</td>';
    return '<td class="num" data-key="' + key + '" data-scale="' + scale + '" data-decimals="' +
        decimals + '">' + (value * scale).toFixed(decimals) + '</td>';
  };
  const degrees = 180 / Math.PI;

  // --- 3D: the validation scans fused with the old and the new model ---
  const radius = Math.max(data.clouds.radius_m, 1e-3);
  const camera = new THREE.PerspectiveCamera(40, 1.25, radius / 100, radius * 20);
  camera.up.set(0, 0, 1);
  camera.position.set(radius * 1.2, -radius * 1.2, radius * 0.9);
  camera.lookAt(0, 0, 0);
  const views = ['before', 'after'].map(function (which) {
    const canvas = document.getElementById('view-' + which);
    const renderer = new THREE.WebGLRenderer({canvas: canvas, preserveDrawingBuffer: true});
    renderer.setPixelRatio(1);
    renderer.setSize(canvas.width, canvas.height, false);
    renderer.setClearColor(0xffffff, 1);
    const scene = new THREE.Scene();
    const geometry = new THREE.BufferGeometry();
    const cloud = data.clouds[which];
    geometry.setAttribute('position', new THREE.BufferAttribute(decode(cloud.positions, Float32Array), 3));
    geometry.setAttribute('color', new THREE.BufferAttribute(decode(cloud.colours, Uint8Array), 3, true));
    scene.add(new THREE.Points(geometry, new THREE.PointsMaterial(
        {size: 2, sizeAttenuation: false, vertexColors: THREE.VertexColors})));
    return {canvas: canvas, renderer: renderer, scene: scene, count: cloud.count};
  });
  const render = function () {
    views.forEach(function (view) { view.renderer.render(view.scene, camera); });
  };
  views.forEach(function (view) {
    const controls = new THREE.OrbitControls(camera, view.canvas);
    controls.addEventListener('change', render);
  });
  render();
  document.body.dataset.rendered = views.map(function (v) { return v.count; }).join(',');
  // Where an element is on the page, in CSS pixels (for a screenshot to be looked at there).
  const place = function (element) {
    const r = element.getBoundingClientRect();
    return [r.left + window.scrollX, r.top + window.scrollY, r.width, r.height].map(Math.round).join(',');
  };
  views.forEach(function (view, i) {
    document.body.dataset['view' + ['Before', 'After'][i]] = place(view.canvas);
  });

  // --- plots (Chart.js) ---
  Chart.defaults.animation = false;
  Chart.defaults.responsive = false;
  const h = data.histogram;
  new Chart(document.getElementById('plot-residuals'), {type: 'bar', data: {
    labels: h.centres_mm.map(function (c) { return c.toFixed(1); }),
    datasets: [
      {label: 'old model (RMS ' + (h.rms_before_m * 1e3).toFixed(3) + ' mm)', data: h.before,
       backgroundColor: 'rgba(180,35,24,0.45)', grouped: false, barPercentage: 1, categoryPercentage: 1},
      {label: 'new model (RMS ' + (h.rms_after_m * 1e3).toFixed(3) + ' mm)', data: h.after,
       backgroundColor: 'rgba(31,119,180,0.55)', grouped: false, barPercentage: 1, categoryPercentage: 1}]},
    options: {plugins: {title: {display: true, text: 'Validation residuals (point to plane)'}},
      scales: {x: {title: {display: true, text: 'residual [mm]'}},
               y: {title: {display: true, text: 'matches'}}}}});

  const it = data.iterations;
  new Chart(document.getElementById('plot-convergence'), {type: 'line', data: {
    labels: it.map(function (_, i) { return i + 1; }),
    datasets: [
      {label: 'RMS before the solve [mm]', data: it.map(function (x) { return x.rms_before_m * 1e3; }), borderColor: '#b42318', yAxisID: 'y'},
      {label: 'RMS after the solve [mm]', data: it.map(function (x) { return x.rms_after_m * 1e3; }), borderColor: '#1f77b4', yAxisID: 'y'},
      {label: '|delta k|', data: it.map(function (x) { return x.delta_k; }), borderColor: '#888', borderDash: [4, 3], yAxisID: 'delta'},
      {label: 'step (what the loop stopped on)', data: it.map(function (x) { return x.step; }), borderColor: '#2ca02c', borderDash: [2, 2], yAxisID: 'delta'}]},
    options: {plugins: {title: {display: true, text: 'Convergence per ICP iteration'}},
      scales: {x: {title: {display: true, text: 'iteration'}},
               y: {title: {display: true, text: 'fit RMS [mm]'}},
               delta: {type: 'logarithmic', position: 'right', title: {display: true, text: '|delta k|, step'}}}}});

  const joints = data.joints;
  const jointValue = function (j, v) { return joints[j].revolute ? v * degrees : v * 1e3; };
  const scanPoints = function (validation) {
    const points = [];
    data.scans.forEach(function (scan) {
      if (scan.validation !== validation) return;
      scan.joints.forEach(function (v, j) { points.push({x: joints[j].name, y: jointValue(j, v)}); });
    });
    return points;
  };
  new Chart(document.getElementById('plot-coverage'), {type: 'bar', data: {
    labels: joints.map(function (j) { return j.name; }),
    datasets: [
      {type: 'line', label: 'fit scans', data: scanPoints(false), showLine: false, borderColor: '#1f77b4', backgroundColor: '#1f77b4', pointRadius: 3},
      {type: 'line', label: 'validation scans', data: scanPoints(true), showLine: false, borderColor: '#ff7f0e', backgroundColor: '#ff7f0e', pointRadius: 3, pointStyle: 'triangle'},
      {label: 'joint limits', data: joints.map(function (j, i) { return [jointValue(i, j.lower), jointValue(i, j.upper)]; }),
       backgroundColor: 'rgba(0,0,0,0.08)', barPercentage: 0.5}]},
    options: {plugins: {title: {display: true, text: 'Joint-space coverage of the scans (deg; mm for prismatic joints)'}}}});

  // The predicted error map: per joint, each bin with configurations at its centre.
  const palette = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2',
                   '#7f7f7f', '#bcbd22', '#17becf'];
  let mapPoints = 0;
  const mapCanvas = document.getElementById('plot-error-map');
  new Chart(mapCanvas, {type: 'line', data: {datasets: data.error_map.map(function (joint, j) {
    const bins = joint.samples.length, scale = joint.prismatic ? 1e3 : degrees;
    const points = [];
    joint.samples.forEach(function (samples, b) {
      if (samples === 0) return;
      points.push({x: (joint.lower + (b + 0.5) * (joint.upper - joint.lower) / bins) * scale,
                   y: joint.sensor_rms_position_m[b] * 1e3});
    });
    mapPoints += points.length;
    const colour = palette[j % palette.length];
    return {label: joint.joint, data: points, borderColor: colour, backgroundColor: colour};
  })},
    options: {plugins: {title: {display: true, text: 'Predicted position error at the sensor (1 sigma) over each joint\'s range'}},
      scales: {x: {type: 'linear', title: {display: true, text: 'joint position [deg; mm for prismatic joints]'}},
               y: {title: {display: true, text: 'predicted RMS [mm]'}}}}});
  document.body.dataset.errorMap = mapPoints;
  document.body.dataset.plotErrorMap = place(mapCanvas);

  const parameterPlot = function (id, unit, scale, title) {
    const chosen = data.parameters.filter(function (p) { return p.unit === unit; });
    const change = chosen.map(function (p) { return (p.calibrated - p.nominal) * scale; });
    new Chart(document.getElementById(id), {type: 'bar', data: {
      labels: chosen.map(function (p) { return p.name; }),
      datasets: [
        {type: 'line', label: 'change', data: change, showLine: false, borderColor: '#1f77b4', backgroundColor: '#1f77b4', pointRadius: 4},
        {label: '+- 1 standard deviation', data: chosen.map(function (p, i) {
           return p.std_dev === null ? null : [change[i] - p.std_dev * scale, change[i] + p.std_dev * scale]; }),
         backgroundColor: 'rgba(31,119,180,0.35)', barThickness: 6}]},
      options: {plugins: {title: {display: true, text: title}}}});
  };
  parameterPlot('plot-angles', 'rad', degrees, 'Angle changes [deg] with standard deviations');
  parameterPlot('plot-translations', 'm', 1e3, 'Translation changes [mm] with standard deviations');

  // --- tables ---
  let rows = '';
  data.parameters.forEach(function (p, i) {
    const key = 'parameters.' + i + '.';
    // a joint's compliance (rad/Nm, docs/engine.md deviation 15) is shown in urad/Nm, the
    // sensor latency (s, deviation 16) in ms
    const shown = p.unit === 'rad' ? degrees : (p.unit === 'rad_per_nm' ? 1e6 : 1e3);
    const suffix = p.unit === 'rad' ? ' deg' :
        (p.unit === 'rad_per_nm' ? ' urad/Nm' : (p.unit === 's' ? ' ms' : ' mm'));
    rows += '<tr><td>' + p.name + '</td>' + num(key + 'nominal_' + p.unit, p.nominal, 1, 9) +
        num(key + 'calibrated_' + p.unit, p.calibrated, 1, 9) + num(key + 'std_dev_' + p.unit, p.std_dev, 1, 9) +
        '<td class="num">' + ((p.calibrated - p.nominal) * shown).toFixed(4) + suffix + '</td></tr>';
  });
  document.getElementById('parameter-rows').innerHTML = rows;
  rows = '';
  it.forEach(function (x, i) {
    const key = 'per_iteration.' + i + '.';
    rows += '<tr><td>' + (i + 1) + '</td>' + num('valid_matches_per_iteration.' + i, x.valid_matches, 1, 0) +
        num(key + 'rms_before_m', x.rms_before_m, 1e3, 4) + num(key + 'rms_after_m', x.rms_after_m, 1e3, 4) +
        num(key + 'delta_k', x.delta_k, 1, 9) +
        (x.step === null ? '<td></td>' : num(key + 'step', x.step, 1, 9)) +
        num(key + 'lm_iterations', x.lm_iterations, 1, 0) +
        num(key + 'time_s', x.time_s, 1, 3) + '</tr>';
  });
  document.getElementById('iteration-rows').innerHTML = rows;
  document.body.dataset.ready = 'yes';
})();
)js";

}  // namespace

std::string RenderPage(const PageParts& parts) {
  std::string page = "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>" +
                     MarkupText(parts.title) + "</title>\n<style>" + kStyle +
                     "</style>\n</head>\n<body>\n";
  page += parts.body_html;
  page += parts.licences_html;
  page +=
      "<script type=\"application/json\" id=\"selfcal-data\">{" + parts.data_json + "}</script>\n";
  page += "<script>\n" + parts.libraries + "\n</script>\n";
  page += std::string("<script>") + kScript + "</script>\n</body></html>\n";
  return page;
}

}  // namespace selfcal::report
