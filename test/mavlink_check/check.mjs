#!/usr/bin/env node
// check.mjs — verify decoded MAVLink messages (decode.mjs output) against the odometry log (CSV).
//
// All math here is this file's own (plain JS, double precision); nothing of the project's code is
// used. Conventions checked (see README.md beside this file for the full list):
//   log rows: T = pose of the current camera in the previous camera frame (OpenCV axes), covariance
//   of xi = (t, rotation vector). Body frame FRD, extrinsic X = (R_bc, p_bc) (camera in body):
//   dT_b = X dT_c X^-1, Sigma_b = J Sigma_c J^T, J = [[R_bc, [p_bc]x R_bc], [0, R_bc]].
//   ODOMETRY per row: velocity t_b/dt, rates r_b/dt, velocity_covariance = Sigma_b/dt^2 (upper
//   triangle, row-major), pose T_lb(k) = T_lb(k-1) dT_b from identity, position covariance from
//   P_k = A P A^T + B Sigma_b B^T, A = [[I, -[R_{k-1} t_b]x], [0, I]], B = diag(R_{k-1}, R_k).
//
//   Two choices the conventions leave open are options (defaults = the project brief):
//   --velocity-frame previous|current: body frame at t_prev (v = t_b/dt, VPD position_delta = t_b)
//     or at t_curr (v = dR_b^T t_b/dt, position_delta = dR_b^T t_b; the ODOMETRY child frame is
//     the body at time_usec, as ROS REP 147, and ArduPilot documents position_delta "rotated to
//     the current MAV_FRAME_BODY_FRD"); with current, velocity_covariance = G Sigma_b G^T/dt^2,
//     G = [[dR_b^T, [dR_b^T t_b]x Jr], [0, I]].
//   --jacobians first-order|exact: the rotation parts of Sigma as small right perturbations
//     (Jr = I, J's lever term [p_bc]x R_bc, B's lower block R_k), or as the covariance of the
//     rotation vector itself (Jr = SO(3) right Jacobian of r_b: J's lever term
//     dR_b [p_bc]x Jr R_bc, B's lower block R_k Jr, G as above).
//
// Usage: node check.mjs --decoded decoded.jsonl --log odometry.csv
//          [--extrinsic R00,R01,R02,R10,R11,R12,R20,R21,R22,px,py,pz] [--expect-vpd | --vpd-only] [--delta-min-ms MS] [--initial-rpy ROLL,PITCH]
//          [--velocity-frame previous|current] [--jacobians first-order|exact]
//          [--sysid 1] [--compid 197] [--min-heartbeats 1] [--allow-msgid ID]... [--allow-untrimmed]
//          [--max-print 200] [--quiet]
// Exit status: 0 all good, 1 mismatches found, 2 unreadable input, 64 usage error.

import fs from 'node:fs';

const MSG_HEARTBEAT = 0;
const MSG_ODOMETRY = 331;
const MSG_VPD = 11011;
const MSG_COMMAND_LONG = 76;  // MAV_CMD_SET_MESSAGE_INTERVAL: the autopilot's ATTITUDE asked for
const MAV_CMD_SET_MESSAGE_INTERVAL = 511;
const MSG_ATTITUDE = 30;
const MAV_TYPE_ONBOARD_CONTROLLER = 18;
const MAV_AUTOPILOT_INVALID = 8;
const MAV_FRAME_LOCAL_FRD = 20;
const MAV_FRAME_BODY_FRD = 12;
const MAV_ESTIMATOR_TYPE_VISION = 2;  // common.xml MAV_ESTIMATOR_TYPE: 2 VISION (3 is VIO)

// ---------------------------------------------------------------------------------------------
// arguments

function usage(msg) {
  process.stderr.write(`check.mjs: ${msg}\n` +
    'usage: node check.mjs --decoded decoded.jsonl --log odometry.csv [--extrinsic R00,..,R22,px,py,pz]\n' +
    '       [--expect-vpd | --vpd-only] [--delta-min-ms MS] [--initial-rpy ROLL,PITCH] [--sysid N] [--compid N] [--min-heartbeats N] [--allow-msgid ID]...\n' +
    '       [--allow-untrimmed] [--velocity-frame previous|current] [--jacobians first-order|exact]\n' +
    '       [--max-print N] [--quiet]\n');
  process.exit(64);
}

function parseArgs(argv) {
  const o = {
    sysid: 1, compid: 197, expectVpd: false, vpdOnly: false, deltaMinMs: 0, minHeartbeats: 1, allowMsgid: new Set(), allowUntrimmed: false,
    maxPrint: 200, quiet: false, velocityFrame: 'previous', jacobians: 'first-order',
    Rbc: [0, 0, 1, 1, 0, 0, 0, 1, 0], pbc: [0, 0, 0],
  };
  const intArg = (name, v, lo, hi) => {
    if (v === undefined || !/^\d+$/.test(v) || Number(v) < lo || Number(v) > hi) usage(`${name} needs an integer in [${lo}, ${hi}]`);
    return Number(v);
  };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const next = () => { if (i + 1 >= argv.length) usage(`${a} needs a value`); return argv[++i]; };
    switch (a) {
      case '--decoded': o.decoded = next(); break;
      case '--log': o.log = next(); break;
      case '--extrinsic': {
        const v = next().split(',').map((s) => Number(s.trim()));
        if (v.length !== 12 || v.some((x) => !Number.isFinite(x))) usage('--extrinsic needs 12 comma-separated numbers: R00..R22 (row-major R_bc), px,py,pz');
        o.Rbc = v.slice(0, 9); o.pbc = v.slice(9, 12);
        break;
      }
      case '--expect-vpd': o.expectVpd = true; break;
      case '--vpd-only': o.expectVpd = true; o.vpdOnly = true; break;
      case '--delta-min-ms': o.deltaMinMs = Number(next()); break;
      case '--initial-rpy': o.initialRpy = next().split(',').map(Number); break;
      case '--sysid': o.sysid = intArg(a, next(), 0, 255); break;
      case '--compid': o.compid = intArg(a, next(), 0, 255); break;
      case '--min-heartbeats': o.minHeartbeats = intArg(a, next(), 0, 1e9); break;
      case '--allow-msgid': o.allowMsgid.add(intArg(a, next(), 0, 16777215)); break;
      case '--allow-untrimmed': o.allowUntrimmed = true; break;
      case '--velocity-frame': o.velocityFrame = next(); if (!['previous', 'current'].includes(o.velocityFrame)) usage('--velocity-frame is previous or current'); break;
      case '--jacobians': o.jacobians = next(); if (!['first-order', 'exact'].includes(o.jacobians)) usage('--jacobians is first-order or exact'); break;
      case '--max-print': o.maxPrint = intArg(a, next(), 0, 1e9); break;
      case '--quiet': o.quiet = true; break;
      case '-h': case '--help': usage('help');
      default: usage(`unknown argument '${a}'`);
    }
  }
  if (!o.decoded || !o.log) usage('--decoded and --log are required');
  // R_bc must be a rotation.
  const RtR = mul3(tr3(o.Rbc), o.Rbc);
  for (let i = 0; i < 9; i++) {
    if (Math.abs(RtR[i] - (i % 4 === 0 ? 1 : 0)) > 1e-6) usage('--extrinsic: R_bc is not orthonormal');
  }
  if (Math.abs(det3(o.Rbc) - 1) > 1e-6) usage('--extrinsic: det(R_bc) is not +1');
  return o;
}

// ---------------------------------------------------------------------------------------------
// small linear algebra (row-major flat arrays)

function mul(a, b, n, m, p) {  // (n x m) * (m x p)
  const c = new Array(n * p).fill(0);
  for (let i = 0; i < n; i++) for (let k = 0; k < m; k++) {
    const aik = a[i * m + k];
    if (aik === 0) continue;
    for (let j = 0; j < p; j++) c[i * p + j] += aik * b[k * p + j];
  }
  return c;
}
function tr(a, n, m) {
  const t = new Array(n * m);
  for (let i = 0; i < n; i++) for (let j = 0; j < m; j++) t[j * n + i] = a[i * m + j];
  return t;
}
const mul3 = (a, b) => mul(a, b, 3, 3, 3);
const tr3 = (a) => tr(a, 3, 3);
const mv3 = (a, v) => mul(a, v, 3, 3, 1);
const mul6 = (a, b) => mul(a, b, 6, 6, 6);
const tr6 = (a) => tr(a, 6, 6);
const add = (a, b) => a.map((x, i) => x + b[i]);
const sub = (a, b) => a.map((x, i) => x - b[i]);
const scale = (a, s) => a.map((x) => x * s);
const norm = (v) => Math.hypot(...v);
const I3 = [1, 0, 0, 0, 1, 0, 0, 0, 1];
function det3(m) {
  return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}
function skew(v) { return [0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0]; }
// 6x6 from four 3x3 blocks
function blocks(a, b, c, d) {
  const m = new Array(36).fill(0);
  const put = (blk, r0, c0) => { for (let i = 0; i < 3; i++) for (let j = 0; j < 3; j++) m[(r0 + i) * 6 + c0 + j] = blk[i * 3 + j]; };
  put(a, 0, 0); put(b, 0, 3); put(c, 3, 0); put(d, 3, 3);
  return m;
}
const Z3 = [0, 0, 0, 0, 0, 0, 0, 0, 0];

// unit quaternion (x, y, z, w) -> rotation matrix
function quatToMat([x, y, z, w]) {
  const n = Math.hypot(x, y, z, w);
  x /= n; y /= n; z /= n; w /= n;
  return [
    1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
    2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
    2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y),
  ];
}
// rotation matrix -> unit quaternion {w, x, y, z} with w >= 0 (Shepperd's method)
function matToQuat(m) {
  const [m00, m01, m02, m10, m11, m12, m20, m21, m22] = m;
  const t = m00 + m11 + m22;
  let w, x, y, z;
  if (t >= m00 && t >= m11 && t >= m22) {
    const s = Math.sqrt(1 + t) * 2; w = s / 4; x = (m21 - m12) / s; y = (m02 - m20) / s; z = (m10 - m01) / s;
  } else if (m00 >= m11 && m00 >= m22) {
    const s = Math.sqrt(1 + m00 - m11 - m22) * 2; w = (m21 - m12) / s; x = s / 4; y = (m01 + m10) / s; z = (m02 + m20) / s;
  } else if (m11 >= m22) {
    const s = Math.sqrt(1 + m11 - m00 - m22) * 2; w = (m02 - m20) / s; x = (m01 + m10) / s; y = s / 4; z = (m12 + m21) / s;
  } else {
    const s = Math.sqrt(1 + m22 - m00 - m11) * 2; w = (m10 - m01) / s; x = (m02 + m20) / s; y = (m12 + m21) / s; z = s / 4;
  }
  const n = Math.hypot(w, x, y, z);
  const sg = w < 0 ? -1 : 1;
  return { w: sg * w / n, x: sg * x / n, y: sg * y / n, z: sg * z / n };
}
// rotation matrix -> rotation vector (axis * angle, angle in [0, pi])
function rotvec(m) {
  const q = matToQuat(m);
  const s = Math.hypot(q.x, q.y, q.z);
  if (s < 1e-12) return [2 * q.x, 2 * q.y, 2 * q.z];
  const angle = 2 * Math.atan2(s, q.w);
  return [q.x / s * angle, q.y / s * angle, q.z / s * angle];
}

// SO(3) right Jacobian: exp(r + d) ~ exp(r) exp(Jr(r) d)
function rightJacobian(r) {
  const th = norm(r);
  const K = skew(r);
  const K2 = mul3(K, K);
  let a, b;
  if (th < 1e-4) { a = 0.5 - th * th / 24; b = 1 / 6 - th * th / 120; } else {
    a = (1 - Math.cos(th)) / (th * th); b = (th - Math.sin(th)) / (th * th * th);
  }
  return I3.map((v, i) => v - a * K[i] + b * K2[i]);
}

// ---------------------------------------------------------------------------------------------
// inputs

function readLog(path) {
  const text = fs.readFileSync(path, 'utf8');
  const lines = text.split(/\r?\n/).filter((l) => l.length > 0);
  if (lines.length === 0) throw new Error(`${path}: empty`);
  const header = lines[0].split(',');
  const col = Object.fromEntries(header.map((h, i) => [h.trim(), i]));
  const need = ['t_prev', 't_curr', 'status', 'inliers', 'tx', 'ty', 'tz', 'qx', 'qy', 'qz', 'qw'];
  for (let i = 0; i < 6; i++) for (let j = 0; j < 6; j++) need.push(`c${i}${j}`);
  for (const n of need) if (!(n in col)) throw new Error(`${path}: column '${n}' missing from header`);
  return lines.slice(1).map((line, r) => {
    const f = line.split(',');
    if (f.length !== header.length) throw new Error(`${path}:${r + 2}: ${f.length} fields, header has ${header.length}`);
    const num = (n) => Number(f[col[n]].trim());  // Number('nan') is NaN, as wanted
    const cov = [];
    for (let i = 0; i < 6; i++) for (let j = 0; j < 6; j++) cov.push(num(`c${i}${j}`));
    // The keyframe chain (0 none, 1 begun here, 2 going on) and the pose's covariance since it
    // began (upper triangle, camera frame, right perturbation); logs without them: none.
    const chain = 'chain' in col ? num('chain') : 0;
    const chainCov = new Array(36).fill(NaN);
    if (chain > 0) for (let i = 0; i < 6; i++) for (let j = i; j < 6; j++) chainCov[i * 6 + j] = chainCov[j * 6 + i] = num(`pc${i}${j}`);
    return {
      chain, chainCov,
      line: r + 2,
      tPrevStr: f[col.t_prev].trim(), tCurrStr: f[col.t_curr].trim(),
      status: f[col.status].trim(),
      t: [num('tx'), num('ty'), num('tz')],
      q: [num('qx'), num('qy'), num('qz'), num('qw')],
      cov,
    };
  });
}

// decimal seconds string -> { us: BigInt floor(seconds * 1e6), decimals, seconds }
function parseSeconds(s) {
  const m = /^(-?)(\d+)(?:\.(\d*))?$/.exec(s);
  if (!m) throw new Error(`bad timestamp '${s}'`);
  const neg = m[1] === '-';
  const frac = m[3] || '';
  const decimals = frac.length;
  const micro = BigInt(m[2]) * 1000000n + BigInt((frac + '000000').slice(0, 6));
  const exact = frac.length <= 6 || /^0*$/.test(frac.slice(6));
  let us = neg ? -micro : micro;
  if (neg && !exact) us -= 1n;  // floor for negative times
  return { us, decimals, seconds: Number(s) };
}

function readDecoded(path) {
  const lines = fs.readFileSync(path, 'utf8').split(/\r?\n/).filter((l) => l.trim().length > 0);
  const packets = [];
  let summary = null;
  lines.forEach((l, i) => {
    let o;
    try { o = JSON.parse(l); } catch (e) { throw new Error(`${path}:${i + 1}: not JSON: ${e.message}`); }
    if (o.summary) summary = o.summary;
    else packets.push(o);
  });
  return { packets, summary };
}

// "NaN"/"Infinity" strings back to numbers (decode.mjs writes non-finite floats as strings)
function num(v) {
  if (typeof v === 'number') return v;
  if (v === 'NaN') return NaN;
  if (v === 'Infinity') return Infinity;
  if (v === '-Infinity') return -Infinity;
  if (typeof v === 'string' && /^-?\d+$/.test(v)) return Number(v);
  return NaN;
}

// ---------------------------------------------------------------------------------------------
// checking

function main() {
  const opt = parseArgs(process.argv.slice(2));
  let rows, decoded;
  try {
    rows = readLog(opt.log);
    decoded = readDecoded(opt.decoded);
  } catch (e) {
    process.stderr.write(`check.mjs: ${e.message}\n`);
    process.exit(2);
  }
  const { packets, summary } = decoded;

  const errors = [];
  const fail = (where, what) => {
    errors.push(`${where}: ${what}`);
    if (!opt.quiet && errors.length <= opt.maxPrint) process.stdout.write(`MISMATCH ${where}: ${what}\n`);
  };
  const fmt = (x) => (typeof x === 'number' ? x.toPrecision(9) : String(x));
  // |got - exp| <= rel*|exp| + abs ; NaN only matches NaN
  const near = (got, exp, rel, abs) => {
    if (Number.isNaN(exp)) return Number.isNaN(got);
    if (!Number.isFinite(got)) return false;
    return Math.abs(got - exp) <= rel * Math.abs(exp) + abs;
  };
  // the closest call among the passing comparisons: how much room the tolerances leave
  let worst = { ratio: 0, at: null };
  const expectNear = (where, name, got, exp, rel, abs) => {
    if (Number.isFinite(got) && Number.isFinite(exp)) {
      const ratio = Math.abs(got - exp) / (rel * Math.abs(exp) + abs);
      if (ratio <= 1 && ratio > worst.ratio) worst = { ratio, at: `${where}: ${name}` };
    }
    if (!near(got, exp, rel, abs)) {
      fail(where, `${name} = ${fmt(got)}, expected ${fmt(exp)} (tolerance ${fmt(rel * Math.abs(exp) + abs)}, diff ${fmt(got - exp)})`);
      return false;
    }
    return true;
  };
  const expectEq = (where, name, got, exp) => {
    if (got !== exp) { fail(where, `${name} = ${got}, expected ${exp}`); return false; }
    return true;
  };

  // ---- the decoder's own account ----
  if (!summary) fail('decoder', 'no summary line: decode.mjs did not finish');
  else {
    for (const k of ['badCrc', 'unknownMsgid', 'undecodable', 'skippedBytes', 'pendingBytes']) {
      if (summary[k]) fail('decoder', `${k} = ${summary[k]} (bad or unreadable bytes on the link)`);
    }
    if (summary.untrimmed && !opt.allowUntrimmed) fail('decoder', `untrimmed = ${summary.untrimmed} (MAVLink 2 payloads must have trailing zero bytes cut)`);
  }

  // ---- every packet ----
  let prevSeq = null;
  let seqGaps = 0;
  const allowed = new Set([MSG_HEARTBEAT, MSG_COMMAND_LONG, ...opt.allowMsgid]);
  if (!opt.vpdOnly) allowed.add(MSG_ODOMETRY);
  if (opt.expectVpd) allowed.add(MSG_VPD);
  const odo = [];
  const vpd = [];
  let heartbeats = 0;
  for (const p of packets) {
    const where = `packet rx=${p.rx} seq=${p.seq} msgid=${p.msgid}${p.name ? ` ${p.name}` : ''}`;
    if (p.crcOk !== true) { fail(where, p.crcOk === false ? 'bad CRC' : 'message id unknown to node-mavlink (CRC not checkable)'); continue; }
    expectEq(where, 'magic', p.magic, 0xFD);
    expectEq(where, 'sysid', p.sysid, opt.sysid);
    expectEq(where, 'compid', p.compid, opt.compid);
    if (p.incompatFlags !== undefined) expectEq(where, 'incompat_flags', p.incompatFlags, 0);
    if (p.trimOk === false && !opt.allowUntrimmed) fail(where, `payload length ${p.payloadLength} violates MAVLink 2 zero-trimming (max ${p.maxPayloadLength})`);
    if (prevSeq !== null && p.seq !== ((prevSeq + 1) & 255)) {
      seqGaps++;
      fail(where, `seq gap: previous ${prevSeq}, got ${p.seq} (${(p.seq - prevSeq - 1 + 256) & 255} missing)`);
    }
    prevSeq = p.seq;
    if (!allowed.has(p.msgid)) fail(where, p.msgid === MSG_VPD ? 'VISION_POSITION_DELTA not expected (pass --expect-vpd if it should be sent)' : 'unexpected message id');
    if (!p.fields) { fail(where, 'fields not decoded'); continue; }
    if (p.msgid === MSG_HEARTBEAT) {
      heartbeats++;
      expectEq(where, 'type', p.fields.type, MAV_TYPE_ONBOARD_CONTROLLER);
      expectEq(where, 'autopilot', p.fields.autopilot, MAV_AUTOPILOT_INVALID);
      expectEq(where, 'mavlink_version', p.fields.mavlink_version, 3);
    } else if (p.msgid === MSG_ODOMETRY) {
      odo.push({ p, nVpdBefore: vpd.length });
    } else if (p.msgid === MSG_VPD) {
      vpd.push({ p, nOdoBefore: odo.length });
    } else if (p.msgid === MSG_COMMAND_LONG) {
      // The one command the program sends: ATTITUDE at a rate, as the MAVLink spec words it
      // (param1 the message id, param2 its interval in microseconds, the others 0).
      expectEq(where, 'command', p.fields.command, MAV_CMD_SET_MESSAGE_INTERVAL);
      expectEq(where, 'param1 (message id)', p.fields.param1, MSG_ATTITUDE);
      if (!(p.fields.param2 > 0)) fail(where, `param2 (interval) ${p.fields.param2} us: not a rate`);
      for (const k of ['param3', 'param4', 'param5', 'param6', 'param7']) expectEq(where, k, p.fields[k], 0);
    }
  }
  if (heartbeats < opt.minHeartbeats) fail('stream', `${heartbeats} HEARTBEAT message(s), expected at least ${opt.minHeartbeats}`);
  // A dropped frame is logged and never sent: one whose stamp does not follow the previous one,
  // and one without depth that the next pair bridges (it starts where the dropped row started).
  const loggedRows = rows.length;
  const bridged = (r, k) => r.status === 'no_depth' && k + 1 < rows.length && rows[k + 1].tPrevStr === r.tPrevStr;
  rows = rows.filter((r, k) => r.status !== 'stamp_not_increasing' && !bridged(r, k));
  // The last row's frame may have been dropped towards a next frame that never came: the count
  // of messages tells.
  if (rows.length > 0 && rows[rows.length - 1].status === 'no_depth' && odo.length === rows.length - 1) rows.pop();
  if (opt.vpdOnly ? odo.length !== 0 : odo.length !== rows.length) fail('stream', `${odo.length} ODOMETRY message(s) for ${rows.length} sent log row(s) (${loggedRows} logged)`);

  // ---- the odometry, row by row ----
  const { Rbc, pbc } = opt;
  const exact = opt.jacobians === 'exact';
  const current = opt.velocityFrame === 'current';
  // R_lb: the body's attitude in the local frame, levelled at the start (--initial-rpy: the
  // autopilot's roll and pitch the program reported using) as Ry(pitch) Rx(roll).
  let R = I3.slice();
  if (opt.initialRpy) {
    const [r0, p0] = opt.initialRpy;
    const Rx = [1, 0, 0, 0, Math.cos(r0), -Math.sin(r0), 0, Math.sin(r0), Math.cos(r0)];
    const Ry = [Math.cos(p0), 0, Math.sin(p0), 0, 1, 0, -Math.sin(p0), 0, Math.cos(p0)];
    R = mul3(Ry, Rx);
  }
  let p = [0, 0, 0];              // position of body in local frame
  let P = new Array(36).fill(0);  // covariance of (position, orientation), left/local perturbations
  let chainOrigin = null;          // where the keyframe chain began: { p, P }
  let pathLen = 0;
  let resetBase = null;
  let resets = 0;
  let failedSinceOk = false;
  let prevOdo = null;
  const okRows = [];  // { row, tb, rb, dtUs } for the VPD check
  // camera motion -> body motion: dT_b = X dT_c X^-1
  const bodyStep = (row) => {
    const Rb = mul3(mul3(Rbc, quatToMat(row.q)), tr3(Rbc));
    const tb = add(add(mv3(Rbc, row.t), pbc), scale(mv3(Rb, pbc), -1));
    return { Rb, tb, rb: rotvec(Rb) };
  };
  const n = opt.vpdOnly ? rows.length : Math.min(rows.length, odo.length);
  let checkedRows = 0;

  for (let k = 0; k < n; k++) {
    const row = rows[k];
    if (opt.vpdOnly) {  // no ODOMETRY: the rows give the deltas VISION_POSITION_DELTA must carry
      if (row.status === 'ok') {
        const { Rb, tb, rb } = bodyStep(row);
        const tCurr = parseSeconds(row.tCurrStr);
        okRows.push({ k, row, Rb, tbPrev: tb, dtUs: tCurr.us - parseSeconds(row.tPrevStr).us, tCurrUs: tCurr.us });
      }
      checkedRows++;
      continue;
    }
    const m = odo[k].p;
    const f = m.fields;
    const where = `row ${k} (csv line ${row.line}, t_curr ${row.tCurrStr}, ${row.status}) / ODOMETRY rx=${m.rx}`;
    checkedRows++;
    const tPrev = parseSeconds(row.tPrevStr);
    const tCurr = parseSeconds(row.tCurrStr);
    const dt = tCurr.seconds - tPrev.seconds;
    // the log prints rounded timestamps: each may be off by half a unit of its last decimal
    const dtUnc = 0.5 * 10 ** -tPrev.decimals + 0.5 * 10 ** -tCurr.decimals;

    // header fields
    const tu = BigInt(f.time_usec);
    const dtu = tu - tCurr.us;
    if (dtu < -1n || dtu > 1n) fail(where, `time_usec = ${tu}, expected ${tCurr.us} (+-1)`);
    // An autopilot's buffers keep samples in time order: time must only move forward.
    if (prevOdo && !(tu > BigInt(prevOdo.fields.time_usec))) fail(where, `time_usec = ${tu} not after the previous ODOMETRY's ${prevOdo.fields.time_usec}`);
    expectEq(where, 'frame_id', f.frame_id, MAV_FRAME_LOCAL_FRD);
    expectEq(where, 'child_frame_id', f.child_frame_id, MAV_FRAME_BODY_FRD);
    expectEq(where, 'estimator_type', f.estimator_type, MAV_ESTIMATOR_TYPE_VISION);
    if (resetBase === null) resetBase = f.reset_counter;

    const ok = row.status === 'ok';
    const vel = ['vx', 'vy', 'vz'].map((x) => num(f[x]));
    const rates = ['rollspeed', 'pitchspeed', 'yawspeed'].map((x) => num(f[x]));
    const vcov = f.velocity_covariance.map(num);
    const pcov = f.pose_covariance.map(num);

    if (ok) {
      if (!(dt > 0)) fail(where, `dt = ${dt} s is not positive`);
      if (failedSinceOk) { resets++; failedSinceOk = false; }
      const { Rb, tb, rb } = bodyStep(row);
      const Jr = exact ? rightJacobian(rb) : I3;
      const J = blocks(Rbc, exact ? mul3(mul3(mul3(Rb, skew(pbc)), Jr), Rbc) : mul3(skew(pbc), Rbc), Z3, Rbc);
      const Sc = row.cov;
      const Sb = mul6(mul6(J, Sc), tr6(J));
      const dtRel = dtUnc / dt;
      // the translation in the frame the velocity is given in, and the covariance of (that, r_b)
      const tv = current ? mv3(tr3(Rb), tb) : tb;
      const G = current ? blocks(tr3(Rb), mul3(skew(tv), Jr), Z3, I3) : null;
      const Sv = current ? mul6(mul6(G, Sb), tr6(G)) : Sb;

      // velocity and rates
      const vTolRel = 1e-5 + dtRel;
      ['vx', 'vy', 'vz'].forEach((name, i) => expectNear(where, name, vel[i], tv[i] / dt, vTolRel, 1e-6));
      ['rollspeed', 'pitchspeed', 'yawspeed'].forEach((name, i) => expectNear(where, name, rates[i], rb[i] / dt, vTolRel, 1e-6));

      // velocity covariance: upper triangle of Sigma_v / dt^2
      {
        const cRel = 1e-4 + 2 * dtRel;
        let idx = 0;
        for (let i = 0; i < 6; i++) for (let j = i; j < 6; j++, idx++) {
          const e = Sv[i * 6 + j] / (dt * dt);
          const scaleIJ = Math.sqrt(Math.abs(Sv[i * 7] * Sv[j * 7])) / (dt * dt);
          expectNear(where, `velocity_covariance[${idx}] (${i},${j})`, vcov[idx], e, cRel, 1e-5 * scaleIJ + 1e-30);
        }
      }

      // quality
      if (!(Number.isInteger(f.quality) && f.quality >= 1 && f.quality <= 100)) fail(where, `quality = ${f.quality}, expected 1..100 on an ok row`);

      // pose integration and covariance propagation
      const Rprev = R;
      const dp = mv3(Rprev, tb);
      const A = blocks(I3, scale(skew(dp), -1), Z3, I3);
      const Rnew = mul3(Rprev, Rb);
      const B = blocks(Rprev, Z3, Z3, mul3(Rnew, Jr));
      P = add(mul6(mul6(A, P), tr6(A)), mul6(mul6(B, Sb), tr6(B)));
      R = Rnew;
      p = add(p, dp);
      // With keyframes the pose's covariance is the chain's: P where it began, carried over the
      // way since (as A above), plus its covariance since then turned into the body frame (the
      // extrinsic's adjoint) and into left perturbations (R rho, R phi).
      if (row.chain === 1 || (row.chain === 2 && !chainOrigin)) chainOrigin = { p: p.slice(), P: P.slice() };
      else if (row.chain === 2 && row.chainCov.every(Number.isFinite)) {
        const Ao = blocks(I3, scale(skew(sub(p, chainOrigin.p)), -1), Z3, I3);
        const Ad = blocks(Rbc, mul3(skew(pbc), Rbc), Z3, Rbc);
        const Bc = mul6(blocks(R, Z3, Z3, R), Ad);
        P = add(mul6(mul6(Ao, chainOrigin.P), tr6(Ao)), mul6(mul6(Bc, row.chainCov), tr6(Bc)));
      }
      pathLen += norm(tb);
      okRows.push({ k, row, Rb, tbPrev: tb, dtUs: tCurr.us - tPrev.us, tCurrUs: tCurr.us });
    } else {
      failedSinceOk = true;
      ['vx', 'vy', 'vz', 'rollspeed', 'pitchspeed', 'yawspeed'].forEach((name, i) => {
        const v = i < 3 ? vel[i] : rates[i - 3];
        if (!Number.isNaN(v)) fail(where, `${name} = ${fmt(v)}, expected NaN on a failed row`);
      });
      const notNan = vcov.map((v, i) => (Number.isNaN(v) ? -1 : i)).filter((i) => i >= 0);
      if (notNan.length) fail(where, `velocity_covariance not NaN at index ${notNan.join(',')} on a failed row`);
      expectEq(where, 'quality', f.quality, -1);
      // No pose at all: PX4 fuses a finite one whatever the quality (EKF2_EV_QMIN 0).
      ['x', 'y', 'z'].forEach((name) => {
        if (!Number.isNaN(num(f[name]))) fail(where, `${name} = ${fmt(num(f[name]))}, expected NaN on a failed row (a stale pose)`);
      });
      f.q.map(num).forEach((v, i) => { if (!Number.isNaN(v)) fail(where, `q[${i}] = ${fmt(v)}, expected NaN on a failed row`); });
      const finitePose = pcov.map((v, i) => (Number.isNaN(v) ? -1 : i)).filter((i) => i >= 0);
      if (finitePose.length) fail(where, `pose_covariance not NaN at index ${finitePose.join(',')} on a failed row`);
    }
    expectEq(where, 'reset_counter', f.reset_counter, (resetBase + resets) & 255);
    if (!ok) { prevOdo = m; continue; }

    // pose (ok rows: the integrated pose)
    const posTolAbs = 1e-6 * (1 + pathLen);
    ['x', 'y', 'z'].forEach((name, i) => expectNear(where, name, num(f[name]), p[i], 1e-5, posTolAbs));
    {
      const qe = matToQuat(R);
      const qExp = [qe.w, qe.x, qe.y, qe.z];
      const qGot = f.q.map(num);
      const dot = qGot.reduce((s, v, i) => s + v * qExp[i], 0);
      const sg = dot < 0 ? -1 : 1;
      qExp.forEach((e, i) => expectNear(where, `q[${i}] (w,x,y,z; sign ${sg > 0 ? 'kept' : 'flipped'})`, sg * qGot[i], e, 1e-5, 2e-6));
    }
    // position block of the pose covariance (exact), orientation variances (positivity)
    {
      const posIdx = [[0, 0, 0], [1, 0, 1], [2, 0, 2], [6, 1, 1], [7, 1, 2], [11, 2, 2]];
      for (const [idx, i, j] of posIdx) {
        const e = P[i * 6 + j];
        const scaleIJ = Math.sqrt(Math.abs(P[i * 7] * P[j * 7]));
        expectNear(where, `pose_covariance[${idx}] (${i},${j})`, pcov[idx], e, 1e-4, 1e-5 * scaleIJ + 1e-30);
      }
      for (const [idx, i] of [[15, 3], [18, 4], [20, 5]]) {
        const v = pcov[idx];
        const mustBePositive = P[i * 7] > 0;
        if (!Number.isFinite(v) || v < 0 || (mustBePositive && !(v > 0))) {
          fail(where, `pose_covariance[${idx}] (orientation variance) = ${fmt(v)}, expected ${mustBePositive ? '> 0' : '>= 0'}`);
        }
      }
      const nonFinite = pcov.map((v, i) => (Number.isFinite(v) ? -1 : i)).filter((i) => i >= 0);
      if (nonFinite.length) fail(where, `pose_covariance not finite at index ${nonFinite.join(',')}`);
    }
    prevOdo = m;
  }

  // ---- VISION_POSITION_DELTA ----
  // The deltas expected: consecutive ok rows composed until they span --delta-min-ms (the
  // program's link.delta_min_interval_ms); a failed row starts the composition again.
  const deltas = [];
  {
    const minUs = BigInt(Math.round(opt.deltaMinMs * 1000));
    let acc = null;
    for (const o of okRows) {
      if (acc && o.k !== acc.lastK + 1) acc = null;
      if (!acc) acc = { R: [1, 0, 0, 0, 1, 0, 0, 0, 1], t: [0, 0, 0], dtUs: 0n };
      acc.t = add(acc.t, mv3(acc.R, o.tbPrev));
      acc.R = mul3(acc.R, o.Rb);
      acc.dtUs += o.dtUs;
      acc.lastK = o.k;
      if (acc.dtUs + 1n >= minUs) {  // a microsecond's slack, as the program allows
        deltas.push({ k: o.k, row: o.row, tb: current ? mv3(tr3(acc.R), acc.t) : acc.t, rb: rotvec(acc.R), dtUs: acc.dtUs, tCurrUs: o.tCurrUs });
        acc = null;
      }
    }
  }
  if (opt.expectVpd) {
    if (vpd.length !== deltas.length) fail('stream', `${vpd.length} VISION_POSITION_DELTA message(s) for ${deltas.length} expected (${okRows.length} ok rows, composed over ${opt.deltaMinMs} ms)`);
    const nv = Math.min(vpd.length, deltas.length);
    for (let j = 0; j < nv; j++) {
      const { p: m, nOdoBefore } = vpd[j];
      const { k, row, tb, rb, dtUs, tCurrUs } = deltas[j];
      const f = m.fields;
      const where = `row ${k} (csv line ${row.line}, t_curr ${row.tCurrStr}) / VISION_POSITION_DELTA rx=${m.rx}`;
      const d1 = BigInt(f.time_usec) - tCurrUs;
      if (d1 < -1n || d1 > 1n) fail(where, `time_usec = ${f.time_usec}, expected ${tCurrUs} (+-1)`);
      const d2 = BigInt(f.time_delta_usec) - dtUs;
      if (d2 < -1n || d2 > 1n) fail(where, `time_delta_usec = ${f.time_delta_usec}, expected ${dtUs} (+-1)`);
      rb.forEach((e, i) => expectNear(where, `angle_delta[${i}]`, num(f.angle_delta[i]), e, 1e-5, 1e-7));
      tb.forEach((e, i) => expectNear(where, `position_delta[${i}]`, num(f.position_delta[i]), e, 1e-5, 1e-7));
      const c = num(f.confidence);
      if (!(c >= 0 && c <= 100)) fail(where, `confidence = ${fmt(c)}, expected 0..100`);
      // sent next to its own ODOMETRY: right before or right after it
      if (!opt.vpdOnly && nOdoBefore !== k && nOdoBefore !== k + 1) fail(where, `sent after ${nOdoBefore} ODOMETRY message(s), expected ${k} or ${k + 1} (next to its row's ODOMETRY)`);
    }
  }

  // ---- summary ----
  const byId = {};
  for (const p of packets) byId[p.msgid] = (byId[p.msgid] || 0) + 1;
  const summaryLine = {
    rows: rows.length, rowsChecked: checkedRows, okRows: okRows.length, messages: packets.length,
    odometry: odo.length, heartbeat: heartbeats, visionPositionDelta: vpd.length, seqGaps,
    velocityFrame: opt.velocityFrame, jacobians: opt.jacobians,
    mismatches: errors.length, result: errors.length ? 'FAIL' : 'PASS',
    closestPassingComparison: { diffOverTolerance: Number(worst.ratio.toPrecision(3)), at: worst.at },
  };
  if (errors.length > opt.maxPrint && !opt.quiet) process.stdout.write(`... ${errors.length - opt.maxPrint} more mismatch(es) not printed\n`);
  process.stdout.write(`check.mjs summary: ${JSON.stringify(summaryLine)}\n`);
  process.exit(errors.length ? 1 : 0);
}

main();
