#include "lmcal/report/html_report.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "lmcal/fit/population.hpp"
#include "lmcal/version.hpp"
#include "findings.hpp"
#include "sections.hpp"

namespace lmcal {

namespace {

using report::escape_xml;
using report::num;
using report::Page;

constexpr const char* kStyle = R"(
body{font:14px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0 auto;max-width:1280px;padding:0 24px 48px;color:#222}
h1{font-size:24px;margin:24px 0 4px}h2{font-size:20px;border-bottom:2px solid #0072B2;margin-top:40px}h3{font-size:16px;margin-top:28px}
nav a{margin-right:16px}.calibrated{background:#f3faf6;border:1px solid #bfe3cf;border-radius:6px;padding:0 16px 8px;margin-top:16px}
.calibrated h2{margin-top:12px}.found{font-size:15px}.found details{font-size:14px;margin-top:8px}dt{font-weight:600;margin-top:4px}.brief{background:#f4f7fb;border:1px solid #d0dbe8;border-radius:6px;padding:8px 16px}
.figures{display:flex;flex-wrap:wrap;gap:12px}figure{margin:0}
table{border-collapse:collapse;margin:8px 0;font-size:13px}th,td{border:1px solid #ddd;padding:3px 8px;text-align:left}
th{background:#f2f2f2}td.num{text-align:right;font-variant-numeric:tabular-nums}
.verdict{padding:6px 10px;border-left:4px solid #999}.verdict.explained{border-color:#D55E00}
.verdict.unexplained,.verdict.partly-explained{border-color:#CC79A7}.verdict.no-significant-discrepancy{border-color:#009E73}
.verdict.empirical-term-found{border-left-style:double;border-left-width:6px;background:#fbf3f8}
.empirical{border:1px dashed #CC79A7;border-radius:6px;padding:0 16px 8px;margin-top:16px}.empirical h4{margin:12px 0 4px}
.warning{color:#9a3b00}code{background:#f4f4f4;padding:1px 4px}
.lmcal-tip{position:fixed;z-index:10;pointer-events:none;max-width:420px;background:#fff;border:1px solid #888;border-radius:4px;
padding:3px 7px;font-size:12px;box-shadow:0 1px 4px rgba(0,0,0,.25)}
)";

// Marks <body data-rendered> with "all N" when every listed plot drew, or with those that
// did not; <body data-errors> collects script errors. Then what only a browser's fonts can
// tell: <body data-clipped> lists text drawn outside its plot (a title cut at both ends),
// <body data-unnamed> plots whose x axis does not show the names it should (runs, units;
// svg data-x-names), <body data-overlap> plots whose x or y tick labels run into each other,
// <body data-lacking> plots with data but without a title or two tick labels on each axis. For
// the browser test; the page itself needs no script.
constexpr const char* kCheck = R"(
window.addEventListener('error',function(e){document.body.dataset.errors=(document.body.dataset.errors||'')+e.message+';'});
window.addEventListener('load',function(){var ids=document.body.dataset.plots.split(' ').filter(Boolean),missing=[];
ids.forEach(function(id){var s=document.querySelector('svg[data-plot="'+id+'"]');var b=s&&s.getBoundingClientRect();
if(!b||!(b.width>0&&b.height>0)||!s.querySelector('.series,text'))missing.push(id)});
var clipped=[],unnamed=[],overlap=[],lacking=[];
document.querySelectorAll('svg.plot').forEach(function(s){var id=s.dataset.plot,p=s.getBoundingClientRect();
s.querySelectorAll('text').forEach(function(t){var r=t.getBoundingClientRect();
if(r.width>0&&(r.left<p.left-0.5||r.right>p.right+0.5||r.top<p.top-0.5||r.bottom>p.bottom+0.5))clipped.push(id+': '+t.textContent)});
var ticks=[].slice.call(s.querySelectorAll('text.x-tick'));
if(s.dataset.xNames!==undefined){var shown=ticks.map(function(t){return t.textContent}),names=s.dataset.xNames.split('|');
var tells=function(t,n){if(t===n)return true;var p=t.slice(0,-1);return t.slice(-1)==='\u2026'&&p.length>0&&n.indexOf(p)===0&&
names.filter(function(m){return m.indexOf(p)===0}).length===1};
if(names.some(function(n){return !shown.some(function(t){return tells(t,n)})}))unnamed.push(id)}
var rs=ticks.map(function(t){return t.getBoundingClientRect()}).sort(function(a,b){return a.left-b.left});
for(var i=1;i<rs.length;i++)if(rs[i].left<rs[i-1].right){overlap.push(id);break}
var ys=[].slice.call(s.querySelectorAll('g.tick-labels text:not(.x-tick)'));
var ry=ys.map(function(t){return t.getBoundingClientRect()}).sort(function(a,b){return a.top-b.top});
for(var j=1;j<ry.length;j++)if(ry[j].top<ry[j-1].bottom-0.5){overlap.push(id+' (y)');break}
if(s.hasAttribute('data-x')&&(!s.querySelector('text.title')||ticks.length<2||ys.length<2))lacking.push(id)});
if(clipped.length)document.body.dataset.clipped=clipped.join('; ');
if(unnamed.length)document.body.dataset.unnamed=unnamed.join(' ');
if(overlap.length)document.body.dataset.overlap=overlap.join(' ');
if(lacking.length)document.body.dataset.lacking=lacking.join(' ');
var injected=[];document.querySelectorAll('*').forEach(function(e){for(var i=0;i<e.attributes.length;i++)
if(/^on/i.test(e.attributes[i].name))injected.push(e.tagName+' '+e.attributes[i].name)});
document.querySelectorAll('img,iframe,object,embed').forEach(function(e){injected.push(e.tagName)});
if(document.scripts.length!==1)injected.push(document.scripts.length+' scripts');
if(injected.length)document.body.dataset.injected=injected.join('; ');
document.body.dataset.rendered=missing.length?'missing '+missing.join(' '):'all '+ids.length});
)";

// Hover: the point or line vertex nearest the pointer (within 10 px, inside the frame) gets a
// tooltip with its values and a ring. A point's values are its <title> (which the page reads
// without script too); a line's are read back from its pixels through the svg's axis scales
// (data-x, data-y: "lo hi px_lo px_hi log"), with its band's ends where it has one. The
// <title>s of a hovered plot are moved into the script's list, so that the browser's own
// tooltip does not show beside it. Text only (textContent): no name from the data becomes markup.
constexpr const char* kHover = R"(
(function(){var tip=null,ring=null;
function scale(s,a){var v=(s.getAttribute('data-'+a)||'').split(' ').map(Number);return v.length===5&&v.every(isFinite)&&v[3]!==v[2]?v:null}
function at(k,p){var v=k[0]+(p-k[2])*(k[1]-k[0])/(k[3]-k[2]);return k[4]?Math.pow(10,v):v}
function shown(k,v){if(k[4]||v===0||Math.abs(v)>=1e7||Math.abs(v)<1e-6)return String(Number(v.toPrecision(4)));
var r=Math.abs((k[1]-k[0])/(k[3]-k[2]))/2;return v.toFixed(Math.max(0,Math.min(12,-Math.floor(Math.log10(r)))))}
function vertices(d){var out=[],re=/[ML](-?[0-9.]+) (-?[0-9.]+)/g,m;while((m=re.exec(d)))out.push([+m[1],+m[2]]);return out}
function points(s){if(s.lmcalPoints)return s.lmcalPoints;var pts=[],kx=scale(s,'x'),ky=scale(s,'y'),named=s.hasAttribute('data-x-names');
var xl=s.getAttribute('data-x-label')||'',yl=s.getAttribute('data-y-label')||'';
s.querySelectorAll('g.data circle').forEach(function(c){var t=c.querySelector('title');if(!t)return;
pts.push({x:+c.getAttribute('cx'),y:+c.getAttribute('cy'),text:t.textContent});c.removeChild(t)});
if(kx&&ky)s.querySelectorAll('g.data path.line').forEach(function(p){var g=p.parentNode,name=g.getAttribute('data-label'),t=p.querySelector('title');
if(t)p.removeChild(t);var band={},b=s.querySelector('path.band[data-series="'+g.getAttribute('data-series')+'"]');
if(b)vertices(b.getAttribute('d')).forEach(function(v){(band[v[0]]=band[v[0]]||[]).push(v[1])});
vertices(p.getAttribute('d')).forEach(function(v){var y=shown(ky,at(ky,v[1])),e=band[v[0]];
if(e&&e.length===2)y+=' ['+shown(ky,at(ky,Math.max(e[0],e[1])))+', '+shown(ky,at(ky,Math.min(e[0],e[1])))+']';
pts.push({x:v[0],y:v[1],text:(name?name+': ':'')+(named?'':xl+' '+shown(kx,at(kx,v[0]))+', ')+yl+' '+y})})});
return s.lmcalPoints=pts}
function hide(){if(tip)tip.hidden=true;if(ring&&ring.parentNode)ring.parentNode.removeChild(ring)}
function hover(s,e){var m=s.getScreenCTM(),f=s.querySelector('rect.frame');if(!m||!f)return hide();
var q=new DOMPoint(e.clientX,e.clientY).matrixTransform(m.inverse()),fx=+f.getAttribute('x'),fy=+f.getAttribute('y');
var fw=+f.getAttribute('width'),fh=+f.getAttribute('height'),best=null,bd=100;
points(s).forEach(function(p){if(p.x<fx-1||p.x>fx+fw+1||p.y<fy-1||p.y>fy+fh+1)return;
var d=(p.x-q.x)*(p.x-q.x)+(p.y-q.y)*(p.y-q.y);if(d<bd){bd=d;best=p}});
if(!best)return hide();
if(!tip){tip=document.createElement('div');tip.className='lmcal-tip';tip.setAttribute('role','tooltip');document.body.appendChild(tip)}
tip.textContent=best.text;tip.hidden=false;var x=e.clientX+14,y=e.clientY+14;
if(x+tip.offsetWidth>innerWidth-4)x=Math.max(4,e.clientX-14-tip.offsetWidth);if(y+tip.offsetHeight>innerHeight-4)y=Math.max(4,e.clientY-14-tip.offsetHeight);
tip.style.left=x+'px';tip.style.top=y+'px';
if(!ring){ring=document.createElementNS('http://www.w3.org/2000/svg','circle');ring.setAttribute('class','hover-ring');ring.setAttribute('r','4.5');
ring.setAttribute('fill','none');ring.setAttribute('stroke','#000');ring.setAttribute('stroke-width','1.5');ring.setAttribute('pointer-events','none')}
ring.setAttribute('cx',best.x);ring.setAttribute('cy',best.y);if(ring.parentNode!==s)s.appendChild(ring)}
document.querySelectorAll('svg.plot').forEach(function(s){s.addEventListener('mousemove',function(e){hover(s,e)});
s.addEventListener('mouseleave',hide)})})();
)";

// The first words: what the calibration found and how sure it is, in sentences (findings.hpp:
// the terminal prints the same); the methods' statements and the terms they use one click away.
void found_section(Page& page, const report::Findings& f) {
  if (f.found.empty()) return;
  page << "<section class=\"found\">\n";
  page.heading(2, "What we found", "found");
  for (const auto& sentence : f.found) page.paragraph(sentence);
  for (const auto& sentence : f.contradictions) page.paragraph(sentence, "warning");
  page.heading(3, "How sure", "how-sure-words");
  for (const auto& sentence : f.how_sure) page.paragraph(sentence);
  page << "<details><summary>The interval methods, what they assume, and the terms used</summary>\n";
  for (const auto& [model, lines] : f.method_details) {
    page << "<h4>" << escape_xml(model) << "</h4>\n";
    for (const auto& line : lines) page.paragraph(line);
  }
  page << "<dl>\n";
  for (const auto& [term, definition] : report::glossary())
    page << "<dt>" << escape_xml(term) << "</dt><dd>" << escape_xml(definition) << "</dd>\n";
  page << "</dl>\n<p>Every method's standard errors side by side, the between-run tests and the per-run estimates: "
          "<a href=\"#how-sure\">How sure: the calibrated model's uncertainty</a>.</p>\n</details>\n</section>\n";
}

// The verdicts, and the published models' headline numbers under their label.
void brief(Page& page, const Calibration& c) {
  page.heading(2, "Verdicts", "verdicts");
  page << "<div class=\"brief\">\n";
  if (c.friction) {
    page << fmt::format("<p><b>Friction</b>, {}: the law fitted to {} samples of {}, residual RMSE {} N.",
                        escape_xml(report::published_label(report::rejects(c.friction_diagnosis))), c.friction_log->size(),
                        report::plural(c.friction->runs.size(), "run"), num(c.friction->rmse_N));
    if (c.friction_diagnosis)
      page << fmt::format(" Diagnosis: <b>{}</b>: {}", escape_xml(c.friction_diagnosis->verdict),
                          escape_xml(report::without_verdict(c.friction_diagnosis->summary)));
    page << "</p>\n";
  }
  if (c.thermal) {
    const auto& a = c.thermal->joint.parameter("alpha");
    page << fmt::format("<p><b>Thermal</b>, {}: heat partition α = {} {} from {}; {}.",
                        escape_xml(report::published_label(report::rejects(c.thermal_diagnosis))), num(a.value),
                        escape_xml(report::interval(a)), report::plural(c.thermal_data->runs.size(), "run"),
                        across_runs(c.thermal->alpha_spread));
    if (c.thermal_diagnosis)
      page << fmt::format(" Diagnosis: <b>{}</b>: {}", escape_xml(c.thermal_diagnosis->verdict),
                          escape_xml(report::without_verdict(c.thermal_diagnosis->summary)));
    // The runs' own α disagreeing beyond their intervals (the per-run plot) is structure the
    // verdict must not hide: Cochran's Q of the per-run fits.
    const RandomEffects& runs = c.thermal->alpha_runs;
    if (runs.k >= 3 && runs.q_p < 0.05)
      page << fmt::format(
          " <span class=\"warning\">But this model's runs' own α differ beyond their intervals (Cochran's Q = {} on {} runs, "
          "{}): either something changes from run to run that {}, or the per-run intervals are too narrow — each takes "
          "its run's heat as exact, and an error in the logged friction moves α in proportion. Read α as an average over "
          "runs that differ, and see the per-run α below.</span>",
          num(runs.q, 3), runs.k, report::p_is(runs.q_p),
          report::rejects(c.thermal_diagnosis) ? "the accepted mechanisms may not cover" : "no mechanism of the library explains");
    page << "</p>\n";
  }
  for (const auto& note : c.notes) page.paragraph("Note: " + note, "warning");
  if (!c.warnings.empty())
    page << fmt::format("<p class=\"warning\">{} warning{} about the data: see <a href=\"#data\">Data loaded</a>.</p>\n",
                        c.warnings.size(), c.warnings.size() > 1 ? "s" : "");
  page << "</div>\n";
}

// What to do next, as the exact commands (paths as the calibration was given them; the files
// named without a folder are this report's neighbours).
void next_steps(Page& page, const Calibration& c) {
  page.heading(2, "Next steps", "next-steps");
  const std::string set = c.set.dir.string();
  std::string logs = c.set.friction_manifest ? c.set.friction_manifest->string() : "";
  for (const auto& log : c.set.friction_logs)
    if (!c.set.friction_manifest) {
      if (!logs.empty()) logs += ' ';
      logs += log.string();
    }
  std::vector<std::pair<std::string, std::string>> steps;
  if (c.calibrated.friction && c.calibrated.thermal)
    steps.emplace_back("Predict the rail's temperature and growth over your machine's duty (a TOML of segments; "
                       "example: examples/duty/two_shifts.toml):",
                       "lmcal predict model.toml duty.toml");
  if (c.plan)
    steps.emplace_back("Log the friction conditions that would narrow the constants most (plan_friction_template.csv: "
                       "fill in the forces), add the file to the set, and calibrate again:",
                       fmt::format("lmcal calibrate {}", set));
  if (c.thermal_plan)
    steps.emplace_back("Run the thermal runs planned next (plan_thermal_manifest.toml lists their conditions), add them to "
                       "the thermal manifest, and calibrate again:",
                       fmt::format("lmcal calibrate {}", set));
  const bool unexplained = (c.friction_diagnosis && c.friction_diagnosis->verdict.starts_with("unexplained")) ||
                           (c.thermal_diagnosis && c.thermal_diagnosis->verdict.starts_with("unexplained"));
  if (unexplained)
    steps.emplace_back("Something is left that no named cause explains (see the verdicts): try a cause you suspect on the "
                       "friction log yourself, and compare its held-out error:",
                       fmt::format("lmcal diagnose friction {} --min-gain 1", logs));
  if (c.friction)
    steps.emplace_back("Refit the law with a cause of your choice, or a constant held (lmcal fit friction --help lists "
                       "them):",
                       fmt::format("lmcal fit friction {} --effect {}", logs,
                                   c.calibrated.friction_causes.empty() ? "seal_drag" : c.calibrated.friction_causes.front()));
  steps.emplace_back("Calibrate every unit of a lot, or an axis every week, and see the population and its drift:",
                     "lmcal fleet FOLDER_OF_SETS --jobs 4");
  page << "<ol>";
  for (const auto& [why, command] : steps) page << "<li>" << escape_xml(why) << " <code>" << escape_xml(command) << "</code></li>";
  page << "</ol>\n";
}

void provenance(Page& page, const Calibration& c) {
  page.heading(2, "Inputs and versions", "inputs");
  std::string command;
  for (const auto& part : c.command) command += (command.empty() ? "" : " ") + part;
  page << "<p>Command: <code>" << escape_xml(command) << "</code></p>\n";
  std::vector<std::vector<std::string>> rows;
  for (const auto& [file, hash] : c.inputs) rows.push_back({file, hash});
  page.table({"input file", "SHA-256"}, rows);
  rows.clear();
  for (const auto& [name, version] : software_versions()) rows.push_back({name, version});
  page.table({"software", "version"}, rows);
  if (c.thermal)
    page.paragraph(fmt::format("Thermal model: {} source, {} scheme, {} segments per half rail, time step {} s, ambient: {}.",
                               to_string(c.thermal_options.source), to_string(c.thermal_options.scheme),
                               c.thermal_options.half_rail_segments, num(c.thermal_options.time_step_s),
                               c.thermal_options.ambient));
}

Page build(const Calibration& c) {
  Page body;
  body.heading(1, "lmcal calibration: " + c.set.name);
  const bool calibrated = c.calibrated.friction || c.calibrated.thermal;
  const report::Findings found = report::findings(c);
  body << "<nav>";
  if (!found.found.empty()) body << "<a href=\"#found\">What we found</a>";
  if (calibrated) body << "<a href=\"#calibrated\">The calibrated model</a>";
  body << "<a href=\"#verdicts\">Verdicts</a>";
  if (calibrated) body << "<a href=\"#how-sure\">How sure</a>";
  if (c.friction) body << "<a href=\"#friction\">Friction (published model)</a>";
  if (c.thermal) body << "<a href=\"#thermal\">Thermal (published model)</a>";
  body << "<a href=\"#next-steps\">Next steps</a><a href=\"#data\">Data loaded</a><a href=\"#inputs\">Inputs and versions</a></nav>\n";
  found_section(body, found);
  report::calibrated_section(body, c);
  brief(body, c);
  next_steps(body, c);
  report::how_sure_section(body, c);
  if (c.friction) report::friction_section(body, c);
  if (c.thermal) report::thermal_section(body, c);
  report::data_section(body, c);
  provenance(body, c);
  return body;
}

}  // namespace

std::string report::html_document(std::string_view title, const Page& body) {
  std::string ids;
  for (const auto& id : body.plot_ids()) ids += (ids.empty() ? "" : " ") + id;
  return fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      "<title>{}</title>\n<style>{}</style>\n</head>\n<body data-plots=\"{}\">\n{}<script>{}{}</script>\n"
      "</body>\n</html>\n",
      escape_xml(title), kStyle, ids, body.html(), kCheck, kHover);
}

std::string calibration_report_html(const Calibration& c) {
  return report::html_document("lmcal calibration: " + c.set.name, build(c));
}

std::vector<std::string> calibration_report_plots(const Calibration& c) { return build(c).plot_ids(); }

}  // namespace lmcal
