#!/usr/bin/env node
// selftest.mjs — proves decode.mjs + check.mjs pass a correct stream and fail wrong ones,
// without the project's C++ encoder.
//
// It synthesises odometry log rows (camera motion + covariance, some failed rows), builds the
// messages the project should send for them — with its own formulation (Rodrigues, quaternion
// products, 4x4 homogeneous transforms), not check.mjs' code — serialises them with node-mavlink's
// MavLinkProtocolV2.serialize, sends them through a real UDP socket (and, where python3 exists,
// a real pty) to decode.mjs, and runs check.mjs on the result. Then it breaks one thing at a
// time (a sign, an axis, a dt factor, a dropped or corrupted frame, ...) and asserts that
// check.mjs fails, and fails for that reason.
//
// Usage: node selftest.mjs [--keep] [--only NAME]     (exit 0 = all cases behaved)

import { spawn, spawnSync } from 'node:child_process';
import dgram from 'node:dgram';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { MavLinkProtocolV2, minimal, common, ardupilotmega, x25crc } from 'node-mavlink';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
const KEEP = args.includes('--keep');
const ONLY = args.includes('--only') ? args[args.indexOf('--only') + 1] : null;
const TMP = fs.mkdtempSync(path.join(os.tmpdir(), 'mavlink-selftest-'));

// ---------------------------------------------------------------------------------------------
// a deterministic PRNG and tiny vector helpers (kept apart from check.mjs on purpose)

let seed = 0x2545F491;
function rand() {  // xorshift32 -> [0, 1)
  seed ^= seed << 13; seed >>>= 0; seed ^= seed >>> 17; seed ^= seed << 5; seed >>>= 0;
  return seed / 4294967296;
}
const randn = () => Math.sqrt(-2 * Math.log(rand() + 1e-12)) * Math.cos(2 * Math.PI * rand());

const M4 = {
  mul(a, b) {
    const c = [];
    for (let r = 0; r < 4; r++) for (let col = 0; col < 4; col++) {
      let s = 0;
      for (let k = 0; k < 4; k++) s += a[r][k] * b[k][col];
      (c[r] ||= [])[col] = s;
    }
    return c;
  },
  fromRt(R, t) { return [[...R[0], t[0]], [...R[1], t[1]], [...R[2], t[2]], [0, 0, 0, 1]]; },
  inv(T) {  // rigid inverse
    const Rt = [0, 1, 2].map((i) => [0, 1, 2].map((j) => T[j][i]));
    const t = [0, 1, 2].map((i) => -(Rt[i][0] * T[0][3] + Rt[i][1] * T[1][3] + Rt[i][2] * T[2][3]));
    return M4.fromRt(Rt, t);
  },
  R(T) { return [0, 1, 2].map((i) => T[i].slice(0, 3)); },
  t(T) { return [T[0][3], T[1][3], T[2][3]]; },
};
const matVec = (A, v) => A.map((row) => row.reduce((s, a, j) => s + a * v[j], 0));
const matMat = (A, B) => A.map((row) => B[0].map((_, j) => row.reduce((s, a, k) => s + a * B[k][j], 0)));
const transpose = (A) => A[0].map((_, j) => A.map((row) => row[j]));

// Rodrigues: rotation vector -> matrix
function rodrigues(r) {
  const th = Math.hypot(...r);
  if (th < 1e-15) return [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
  const [x, y, z] = r.map((v) => v / th);
  const c = Math.cos(th), s = Math.sin(th), C = 1 - c;
  return [
    [c + x * x * C, x * y * C - z * s, x * z * C + y * s],
    [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
    [z * x * C - y * s, z * y * C + x * s, c + z * z * C],
  ];
}
// rotation vector -> quaternion [w, x, y, z]
function rvToQuat(r) {
  const th = Math.hypot(...r);
  if (th < 1e-15) return [1, 0, 0, 0];
  const s = Math.sin(th / 2) / th;
  return [Math.cos(th / 2), r[0] * s, r[1] * s, r[2] * s];
}
function qmul([aw, ax, ay, az], [bw, bx, by, bz]) {
  return [
    aw * bw - ax * bx - ay * by - az * bz,
    aw * bx + ax * bw + ay * bz - az * by,
    aw * by - ax * bz + ay * bw + az * bx,
    aw * bz + ax * by - ay * bx + az * bw,
  ];
}
function qrot(q, v) {  // rotate v by unit quaternion q
  const [w, x, y, z] = qmul(qmul(q, [0, ...v]), [q[0], -q[1], -q[2], -q[3]]);
  void w;
  return [x, y, z];
}
function qToR(q) { return [[1, 0, 0], [0, 1, 0], [0, 0, 1]].map((e) => qrot(q, e)).reduce((R, col, j) => { col.forEach((v, i) => { R[i][j] = v; }); return R; }, [[], [], []]); }
const crossMat = ([x, y, z]) => [[0, -z, y], [z, 0, -x], [-y, x, 0]];
function block6(A, B, C, D) {
  return [0, 1, 2, 3, 4, 5].map((i) => [0, 1, 2, 3, 4, 5].map((j) => {
    const M = i < 3 ? (j < 3 ? A : B) : (j < 3 ? C : D);
    return M[i % 3][j % 3];
  }));
}
const Z33 = [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
const I33 = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
const sandwich = (A, S) => matMat(matMat(A, S), transpose(A));
// rotation matrix -> rotation vector (angles below ~3 rad are all this test uses)
function logR(R) {
  const c = Math.min(1, Math.max(-1, (R[0][0] + R[1][1] + R[2][2] - 1) / 2));
  const th = Math.acos(c);
  const v = [R[2][1] - R[1][2], R[0][2] - R[2][0], R[1][0] - R[0][1]];
  const k = th < 1e-8 ? 0.5 : th / (2 * Math.sin(th));
  return v.map((x) => x * k);
}
// central-difference Jacobian of f: R^n -> R^m at x (rows = outputs)
function numJac(f, x, h = 1e-6) {
  const cols = x.map((_, j) => {
    const xp = x.slice(); xp[j] += h;
    const xm = x.slice(); xm[j] -= h;
    const fp = f(xp), fm = f(xm);
    return fp.map((v, i) => (v - fm[i]) / (2 * h));
  });
  return cols[0].map((_, i) => cols.map((col) => col[i]));
}
const add6 = (A, B) => A.map((row, i) => row.map((v, j) => v + B[i][j]));

// ---------------------------------------------------------------------------------------------
// the scenario: log rows + the messages the program should send for them

function makeRows(n, failedAt) {
  const rows = [];
  let tUs = 1305031102175304n;
  for (let k = 0; k < n; k++) {
    const dtUs = BigInt(30000 + Math.floor(rand() * 8000));  // 30..38 ms, uneven
    const tPrevUs = tUs, tCurrUs = tUs + dtUs;
    tUs = tCurrUs;
    const ok = !failedAt.includes(k);
    // camera motion: mostly forward (z) with some lateral motion, a few mrad..0.25 rad rotation
    const rc = ok ? [0.02 * randn(), 0.05 * randn(), 0.01 * randn()] : [0, 0, 0];
    if (ok && k === 1) rc[1] = 0.25;  // one large-ish rotation
    const tc = ok ? [0.01 * randn(), 0.005 * randn(), 0.03 + 0.01 * randn()] : [0, 0, 0];
    let cov = null;
    if (ok) {  // SPD: L L^T, translation sd ~ mm, rotation sd ~ mrad, with correlations
      const L = [0, 1, 2, 3, 4, 5].map((i) => [0, 1, 2, 3, 4, 5].map((j) => (j > i ? 0 : (j === i ? 1 : 0.3 * randn()) * (i < 3 ? 2e-3 : 1.5e-3))));
      cov = matMat(L, transpose(L));
    }
    rows.push({ tPrevUs, tCurrUs, ok, status: ok ? 'ok' : (k % 2 ? 'too_few_matches' : 'ransac_failed'), rc, tc, cov });
  }
  return rows;
}

const usToStr = (us) => `${us / 1000000n}.${String(us % 1000000n).padStart(6, '0')}`;

function writeCsv(file, rows) {
  const head = ['t_prev', 't_curr', 'status', 'inliers', 'tx', 'ty', 'tz', 'qx', 'qy', 'qz', 'qw'];
  for (let i = 0; i < 6; i++) for (let j = 0; j < 6; j++) head.push(`c${i}${j}`);
  const lines = [head.join(',')];
  for (const r of rows) {
    const q = rvToQuat(r.rc);  // w >= 0 for |angle| < pi
    const f = [usToStr(r.tPrevUs), usToStr(r.tCurrUs), r.status, r.ok ? 120 : 0,
      ...r.tc.map((v) => v.toPrecision(9)), q[1].toPrecision(9), q[2].toPrecision(9), q[3].toPrecision(9), q[0].toPrecision(9)];
    for (let i = 0; i < 6; i++) for (let j = 0; j < 6; j++) f.push(r.ok ? r.cov[i][j].toExponential(6) : 'nan');
    lines.push(f.join(','));
  }
  fs.writeFileSync(file, lines.join('\n') + '\n');
}

// Messages as plain descriptions; serialised later so that mutations can act on either level.
// frame: 'previous' | 'current' (body frame of velocity and VPD position_delta);
// exact: covariances by numerical differentiation of the exact maps (rotation-vector
// parametrisation), instead of the first-order closed forms of the brief.
function buildMessages(rows, { Rbc, pbc, vpd, heartbeatEvery = 3, sysid = 1, compid = 197, seq0 = 250, noLever = false, frame = 'previous', exact = false }) {
  const X = M4.fromRt(Rbc, pbc);
  const Xinv = M4.inv(X);
  const Jm = block6(Rbc, matMat(crossMat(pbc), Rbc), Z33, Rbc);
  const bodyOf = (xi) => {  // (t_c, r_c) -> (t_b, r_b)
    const Tb = M4.mul(M4.mul(X, M4.fromRt(rodrigues(xi.slice(3)), xi.slice(0, 3))), Xinv);
    return [...M4.t(Tb), ...logR(M4.R(Tb))];
  };
  let q = [1, 0, 0, 0];
  let pos = [0, 0, 0];
  let P = block6(Z33, Z33, Z33, Z33);
  let reset = 0, failedBefore = false;
  let pose = { x: 0, y: 0, z: 0, q: [1, 0, 0, 0] };
  const out = [];
  const heartbeat = () => {
    const m = new minimal.Heartbeat();
    m.type = 18; m.autopilot = 8; m.baseMode = 0; m.customMode = 0; m.systemStatus = 4; m.mavlinkVersion = 3;
    out.push({ msg: m });
  };
  rows.forEach((r, k) => {
    if (k % heartbeatEvery === 0) heartbeat();
    const m = new common.Odometry();
    m.timeUsec = r.tCurrUs;  // the CSV prints exact microseconds here
    m.frameId = 20; m.childFrameId = 12; m.estimatorType = 2;
    const info = { row: k, ok: r.ok };
    if (r.ok) {
      if (failedBefore) { reset = (reset + 1) & 255; failedBefore = false; }
      const dt = Number(r.tCurrUs - r.tPrevUs) / 1e6;
      // read back what the CSV says (rounded), as the program's log would be read
      const Tc = M4.fromRt(rodrigues(r.rc), r.tc);
      const Tb = M4.mul(M4.mul(X, Tc), Xinv);
      const tb = M4.t(Tb);
      const rb = matVec(Rbc, r.rc);  // R_bc exp([r]x) R_bc^T = exp([R_bc r]x)
      const Sb = sandwich(exact ? numJac(bodyOf, [...r.tc, ...r.rc]) : Jm, r.cov);
      // translation in the velocity's frame, and the covariance of (it, r_b)
      const velOf = (xi) => [...matVec(transpose(rodrigues(xi.slice(3))), xi.slice(0, 3)), ...xi.slice(3)];
      const tv = frame === 'current' ? velOf([...tb, ...rb]).slice(0, 3) : tb;
      const G = frame === 'current'
        ? (exact ? numJac(velOf, [...tb, ...rb]) : block6(transpose(rodrigues(rb)), crossMat(tv), Z33, I33))
        : null;
      const Sv = G ? sandwich(G, Sb) : Sb;
      m.vx = tv[0] / dt; m.vy = tv[1] / dt; m.vz = tv[2] / dt;
      m.rollspeed = rb[0] / dt; m.pitchspeed = rb[1] / dt; m.yawspeed = rb[2] / dt;
      m.velocityCovariance = [];
      for (let i = 0; i < 6; i++) for (let j = i; j < 6; j++) m.velocityCovariance.push(Sv[i][j] / (dt * dt));
      m.quality = 40 + (k % 50);
      // pose and covariance propagation
      const Rprev = qToR(q);
      const dp = qrot(q, tb);
      const qb = rvToQuat(rb);
      const qNew = qmul(q, qb);
      let A = block6(I33, noLever ? Z33 : crossMat(dp.map((v) => -v)), Z33, I33);
      let B = block6(Rprev, Z33, Z33, qToR(qNew));
      if (exact) {  // error state (dp, dth) with R = exp(dth) R^, inputs perturbed additively
        const Rk = qToR(qNew);
        const step = (e) => {
          const Rp = matMat(rodrigues(e.slice(3, 6)), Rprev);
          const tbp = tb.map((v, i) => v + e[6 + i]);
          const rbp = rb.map((v, i) => v + e[9 + i]);
          const pk = matVec(Rp, tbp).map((v, i) => v + e[i] - dp[i]);
          return [...pk, ...logR(matMat(matMat(Rp, rodrigues(rbp)), transpose(Rk)))];
        };
        const AB = numJac(step, new Array(12).fill(0));
        A = AB.map((row) => row.slice(0, 6));
        B = AB.map((row) => row.slice(6, 12));
      }
      P = add6(sandwich(A, P), sandwich(B, Sb));
      q = qNew;
      pos = pos.map((v, i) => v + dp[i]);
      pose = { x: pos[0], y: pos[1], z: pos[2], q: q.slice() };
      Object.assign(info, { tb: tv, rb, tc: r.tc, rc: r.rc, dt, dtUs: r.tCurrUs - r.tPrevUs });
    } else {
      failedBefore = true;
      m.vx = m.vy = m.vz = NaN; m.rollspeed = m.pitchspeed = m.yawspeed = NaN;
      m.velocityCovariance = new Array(21).fill(NaN);
      m.quality = -1;
    }
    if (r.ok) {
      m.x = pose.x; m.y = pose.y; m.z = pose.z; m.q = pose.q.slice();
      // pose covariance: position block from P; orientation block: some positive stand-in
      // (its roll/pitch/yaw conversion is the encoder's business, only positivity is checked)
      m.poseCovariance = [];
      for (let i = 0; i < 6; i++) for (let j = i; j < 6; j++) m.poseCovariance.push(i < 3 && j < 3 ? P[i][j] : (i === j ? P[i][i] : 0));
    } else {  // a failed row carries no pose at all
      m.x = m.y = m.z = NaN; m.q = [NaN, NaN, NaN, NaN];
      m.poseCovariance = new Array(21).fill(NaN);
    }
    m.resetCounter = reset;
    out.push({ msg: m, info });
    if (vpd && r.ok) {
      const v = new ardupilotmega.VisionPositionDelta();
      v.timeUsec = r.tCurrUs; v.timeDeltaUsec = info.dtUs;
      v.angleDelta = info.rb.slice(); v.positionDelta = info.tb.slice(); v.confidence = 80;
      out.push({ msg: v, info });
    }
  });
  return out.map((e, i) => ({ ...e, seq: (seq0 + i) & 255, sysid, compid }));
}

function serialize(list) {
  return list.map((e) => e.raw || new MavLinkProtocolV2(e.sysid, e.compid).serialize(e.msg, e.seq));
}

// a MAVLink 2 frame that keeps its trailing zero bytes (what a non-conforming encoder would send)
function serializeUntrimmed(e) {
  const C = e.msg.constructor;
  const trimmed = new MavLinkProtocolV2(e.sysid, e.compid).serialize(e.msg, e.seq);
  const buf = Buffer.alloc(10 + C.PAYLOAD_LENGTH + 2);
  trimmed.copy(buf, 0, 0, trimmed.length - 2);
  buf[1] = C.PAYLOAD_LENGTH;
  buf.writeUInt16LE(x25crc(buf, 1, 2, C.MAGIC_NUMBER), buf.length - 2);
  return buf;
}
// recompute the CRC of a hand-edited frame (so that only the edit is wrong)
function refreshCrc(buf, magicNumber) {
  buf.writeUInt16LE(x25crc(buf, 1, 2, magicNumber), buf.length - 2);
  return buf;
}

// ---------------------------------------------------------------------------------------------
// running decode.mjs and check.mjs

function runDecoder(frames, { count, chunk = null, transport = 'udp' }) {
  const outFile = path.join(TMP, `decoded-${process.hrtime.bigint()}.jsonl`);
  const all = Buffer.concat(frames);
  if (transport !== 'udp') {
    const binFile = outFile.replace(/\.jsonl$/, '.bin');
    fs.writeFileSync(binFile, all);
    // The two ways the project's C++ test can wire a pty:
    //  'pty-slave':  decoder on the slave path (--serial), bytes written into the master;
    //  'pty-master-raw' / 'pty-master-cooked': the writer owns the slave as its serial port (with
    //  or without putting it in raw mode, as the program under test must), decoder reads the master (--fd).
    const decode = JSON.stringify(path.join(HERE, 'decode.mjs'));
    const decArgs = `'--count', '${count}', '--timeout-ms', '1500', '--out', ${JSON.stringify(outFile)}`;
    const py = [
      'import os, pty, subprocess, sys, tty',
      'm, s = pty.openpty()',
      transport === 'pty-slave'
        ? `p = subprocess.Popen(['node', ${decode}, '--serial', os.ttyname(s), ${decArgs}], stderr=subprocess.PIPE)\nw = m`
        : `${transport === 'pty-master-raw' ? 'tty.setraw(s)' : 'pass'}\np = subprocess.Popen(['node', ${decode}, '--fd', str(m), ${decArgs}], stderr=subprocess.PIPE, pass_fds=(m,))\nw = s`,
      'line = p.stderr.readline().decode()',
      'assert line.startswith("READY"), line',
      `data = open(${JSON.stringify(binFile)}, "rb").read()`,
      'for i in range(0, len(data), 64):',
      '    os.write(w, data[i:i+64])',
      'rc = p.wait(timeout=30)',
      'sys.stderr.write(p.stderr.read().decode())',
      'sys.exit(rc)',
    ].join('\n');
    const r = spawnSync('python3', ['-c', py], { encoding: 'utf8', timeout: 60000 });
    return Promise.resolve({ code: r.status, stderr: r.stderr, outFile });
  }
  return new Promise((resolve, reject) => {
    const child = spawn(process.execPath, [path.join(HERE, 'decode.mjs'), '--udp', '0', '--count', String(count),
      '--timeout-ms', '600', '--linger-ms', '100', '--max-ms', '30000', '--out', outFile], { stdio: ['ignore', 'ignore', 'pipe'] });
    let err = '';
    let sent = false;
    child.stderr.on('data', async (d) => {
      err += d;
      const m = /READY udp ([\d.]+):(\d+)/.exec(err);
      if (m && !sent) {
        sent = true;
        const sock = dgram.createSocket('udp4');
        // one datagram per frame (as a MAVLink UDP endpoint does), or the byte stream chopped up
        const grams = chunk ? Array.from({ length: Math.ceil(all.length / chunk) }, (_, i) => all.subarray(i * chunk, (i + 1) * chunk)) : frames;
        for (const g of grams) {
          await new Promise((res, rej) => sock.send(g, Number(m[2]), m[1], (e) => (e ? rej(e) : res())));
          await new Promise((res) => setTimeout(res, 1));
        }
        sock.close();
      }
    });
    child.on('error', reject);
    child.on('exit', (code) => resolve({ code, stderr: err, outFile }));
  });
}

function runCheck(decodedFile, csvFile, extra) {
  const r = spawnSync(process.execPath, [path.join(HERE, 'check.mjs'), '--decoded', decodedFile, '--log', csvFile, '--max-print', '20', ...extra],
    { encoding: 'utf8', timeout: 60000 });
  return { code: r.status, out: r.stdout + r.stderr };
}

// ---------------------------------------------------------------------------------------------
// the cases

const DEFAULT_RBC = [[0, 0, 1], [1, 0, 0], [0, 1, 0]];
// a camera tilted down by 20 deg about the body y axis and mounted 12 cm forward, 3 cm right, 5 cm down
const tilt = rodrigues([0, -20 * Math.PI / 180, 0]);
const CUSTOM_RBC = matMat(tilt, DEFAULT_RBC);
const CUSTOM_PBC = [0.12, 0.03, 0.05];
const customArg = ['--extrinsic', [...CUSTOM_RBC.flat(), ...CUSTOM_PBC].map((v) => v.toPrecision(17)).join(',')];

const FAILED = [3, 4, 8];
const N = 11;

const rows = makeRows(N, FAILED);
const csv = path.join(TMP, 'odometry.csv');
writeCsv(csv, rows);

const base = () => buildMessages(rows, { Rbc: DEFAULT_RBC, pbc: [0, 0, 0], vpd: false });
const baseVpd = () => buildMessages(rows, { Rbc: CUSTOM_RBC, pbc: CUSTOM_PBC, vpd: true });
const exactCur = () => buildMessages(rows, { Rbc: CUSTOM_RBC, pbc: CUSTOM_PBC, vpd: true, frame: 'current', exact: true });
const odoOf = (list, k) => list.find((e) => e.msg instanceof common.Odometry && e.info.row === k);
const vpdOf = (list, k) => list.find((e) => e.msg instanceof ardupilotmega.VisionPositionDelta && e.info.row === k);
const renumber = (list) => list.map((e, i) => ({ ...e, seq: (250 + i) & 255 }));
const OK_ROW = 1;  // the large-rotation row
const OK_ROW_AFTER_FAIL = 5;

const cases = [
  // --- must pass ---
  { name: 'pass: default extrinsic, one datagram per frame', expect: 'pass', list: base() },
  { name: 'pass: custom extrinsic with offset, VPD', expect: 'pass', list: baseVpd(), check: [...customArg, '--expect-vpd'] },
  { name: 'pass: byte stream chopped into 7-byte datagrams', expect: 'pass', list: baseVpd(), chunk: 7, check: [...customArg, '--expect-vpd'] },
  { name: 'pass: pty, decoder on the slave (--serial)', expect: 'pass', list: baseVpd(), transport: 'pty-slave', check: [...customArg, '--expect-vpd'] },
  { name: 'pass: pty, writer put its slave in raw mode, decoder on the master (--fd)', expect: 'pass', list: baseVpd(), transport: 'pty-master-raw', check: [...customArg, '--expect-vpd'] },
  { name: 'pass: current-frame velocity, exact Jacobians (numerical), lever arm, VPD', expect: 'pass', list: exactCur(), check: [...customArg, '--expect-vpd', '--velocity-frame', 'current', '--jacobians', 'exact'] },
  { name: 'pass: current-frame velocity, first-order Jacobians', expect: 'pass', list: buildMessages(rows, { Rbc: CUSTOM_RBC, pbc: CUSTOM_PBC, vpd: true, frame: 'current' }), check: [...customArg, '--expect-vpd', '--velocity-frame', 'current'] },
  // --- must fail, and say why ---
  { name: 'current-frame velocity checked as previous-frame', why: ['vx =', 'vy =', 'vz ='], list: exactCur(), check: [...customArg, '--expect-vpd'] },
  { name: 'previous-frame velocity checked as current-frame', why: ['vx =', 'vy =', 'vz ='], vpd: true, check: [...customArg, '--expect-vpd', '--velocity-frame', 'current', '--jacobians', 'exact'] },
  { name: 'exact-Jacobian covariances checked as first-order', why: ['velocity_covariance[', 'pose_covariance['], list: exactCur(), check: [...customArg, '--expect-vpd', '--velocity-frame', 'current'] },
  { name: 'first-order covariances checked as exact', why: ['velocity_covariance[', 'pose_covariance['], list: buildMessages(rows, { Rbc: CUSTOM_RBC, pbc: CUSTOM_PBC, vpd: true, frame: 'current' }), check: [...customArg, '--expect-vpd', '--velocity-frame', 'current', '--jacobians', 'exact'] },
  { name: 'vx sign flipped', why: 'vx =', mutate: (l) => { odoOf(l, OK_ROW).msg.vx *= -1; } },
  { name: 'vy and vz swapped (axis swap)', why: 'vy =', mutate: (l) => { const m = odoOf(l, OK_ROW).msg; [m.vy, m.vz] = [m.vz, m.vy]; } },
  { name: 'velocity not divided by dt', why: 'vz =', mutate: (l) => { const m = odoOf(l, OK_ROW).msg; const dt = odoOf(l, OK_ROW).info.dt; m.vx *= dt; m.vy *= dt; m.vz *= dt; } },
  { name: 'rates in camera axes instead of body axes', why: 'rollspeed =', mutate: (l) => { const e = odoOf(l, OK_ROW); [e.msg.rollspeed, e.msg.pitchspeed, e.msg.yawspeed] = e.info.rc.map((v) => v / e.info.dt); } },
  { name: 'velocity covariance not divided by dt^2', why: 'velocity_covariance[', mutate: (l) => { const e = odoOf(l, OK_ROW); e.msg.velocityCovariance = e.msg.velocityCovariance.map((v) => v * e.info.dt * e.info.dt); } },
  { name: 'velocity covariance off-diagonal sign flipped', why: 'velocity_covariance[1]', mutate: (l) => { odoOf(l, OK_ROW).msg.velocityCovariance[1] *= -1; } },
  { name: 'pose quaternion conjugated', why: 'q[', mutate: (l) => { const q = odoOf(l, 2).msg.q; odoOf(l, 2).msg.q = [q[0], -q[1], -q[2], -q[3]]; } },
  { name: 'pose quaternion in x,y,z,w order', why: 'q[', mutate: (l) => { const q = odoOf(l, 2).msg.q; odoOf(l, 2).msg.q = [q[1], q[2], q[3], q[0]]; } },
  { name: 'position variance 0.1% off', why: 'pose_covariance[0]', mutate: (l) => { odoOf(l, 6).msg.poseCovariance[0] *= 1.001; } },
  { name: 'position covariance propagated without the A P A^T lever term', why: 'pose_covariance[', mutate: () => buildMessages(rows, { Rbc: DEFAULT_RBC, pbc: [0, 0, 0], vpd: false, noLever: true }) },
  { name: 'orientation variance zero', why: 'orientation variance', mutate: (l) => { odoOf(l, 2).msg.poseCovariance[18] = 0; } },
  { name: 'NaN in pose covariance', why: 'pose_covariance', mutate: (l) => { odoOf(l, 2).msg.poseCovariance[3] = NaN; } },
  { name: 'time_usec off by 2 us', why: 'time_usec =', mutate: (l) => { odoOf(l, 2).msg.timeUsec += 2n; } },
  { name: 'frame_id NED instead of FRD', why: 'frame_id =', mutate: (l) => { odoOf(l, 2).msg.frameId = 1; } },
  { name: 'estimator_type not VISION', why: 'estimator_type =', mutate: (l) => { odoOf(l, 2).msg.estimatorType = 0; } },
  { name: 'reset_counter not incremented after failure', why: 'reset_counter =', mutate: (l) => { for (const e of l) if (e.info && e.info.row >= OK_ROW_AFTER_FAIL) e.msg.resetCounter -= 1; } },
  { name: 'failed row with zero velocity instead of NaN', why: 'expected NaN on a failed row', mutate: (l) => { const m = odoOf(l, FAILED[0]).msg; m.vx = m.vy = m.vz = 0; } },
  { name: 'failed row velocity covariance zero', why: 'velocity_covariance not NaN', mutate: (l) => { odoOf(l, FAILED[0]).msg.velocityCovariance = new Array(21).fill(0); } },
  { name: 'failed row repeats the last pose (stale pose)', why: 'expected NaN on a failed row', mutate: (l) => {
    const prev = odoOf(l, FAILED[0] - 1).msg, m = odoOf(l, FAILED[0]).msg;
    m.x = prev.x; m.y = prev.y; m.z = prev.z; m.q = prev.q.slice(); } },
  { name: 'failed row with a finite attitude', why: 'q[0] =', mutate: (l) => { odoOf(l, FAILED[0]).msg.q = [1, 0, 0, 0]; } },
  { name: 'failed row with a finite pose covariance', why: 'pose_covariance not NaN', mutate: (l) => { odoOf(l, FAILED[0]).msg.poseCovariance = new Array(21).fill(1e-4); } },
  { name: 'time_usec repeated (a duplicated frame sent)', why: 'not after the previous', mutate: (l) => { odoOf(l, 3).msg.timeUsec = odoOf(l, 2).msg.timeUsec; } },
  { name: 'quality 0 on an ok row', why: 'quality =', mutate: (l) => { odoOf(l, 2).msg.quality = 0; } },
  { name: 'quality not -1 on a failed row', why: 'quality =', mutate: (l) => { odoOf(l, FAILED[1]).msg.quality = 0; } },
  { name: 'one ODOMETRY dropped (seq kept contiguous)', why: 'ODOMETRY message(s) for', mutate: (l) => renumber(l.filter((e) => e !== odoOf(l, 6))) },
  { name: 'one HEARTBEAT lost on the link (seq gap)', why: 'seq gap', mutate: (l) => { const hb = l.filter((e) => e.msg instanceof minimal.Heartbeat)[1]; return l.filter((e) => e !== hb); } },
  { name: 'no HEARTBEAT at all', why: 'HEARTBEAT message(s)', mutate: (l) => renumber(l.filter((e) => !(e.msg instanceof minimal.Heartbeat))) },
  { name: 'HEARTBEAT with wrong type', why: 'type =', mutate: (l) => { l[0].msg.type = 2; } },
  { name: 'wrong compid', why: 'compid =', mutate: (l) => { odoOf(l, 2).compid = 1; } },
  { name: 'wrong sysid', why: 'sysid =', mutate: (l) => { odoOf(l, 2).sysid = 42; } },
  { name: 'one byte corrupted (bad CRC)', why: 'badCrc', frames: (f, l) => { const i = l.indexOf(odoOf(l, 2)); f[i] = Buffer.from(f[i]); f[i][40] ^= 0x10; return f; } },
  { name: 'unknown message id on the link', why: 'unknownMsgid', frames: (f) => {
    const b = Buffer.from([0xFD, 4, 0, 0, 0, 1, 197, 0xDE, 0xBC, 0x0A, 1, 2, 3, 4, 0, 0]);
    refreshCrc(b, 7);
    return [...f.slice(0, 5), b, ...f.slice(5)];
  } },
  { name: 'MAVLink 1 frame', why: 'magic = 254', frames: (f, l) => {
    const e = l[0];
    const C = e.msg.constructor;
    const v1 = Buffer.alloc(6 + C.PAYLOAD_LENGTH + 2);
    v1[0] = 0xFE; v1[1] = C.PAYLOAD_LENGTH; v1[2] = e.seq; v1[3] = e.sysid; v1[4] = e.compid; v1[5] = C.MSG_ID;
    f[0].copy(v1, 6, 10, f[0].length - 2);
    f[0] = refreshCrc(v1, C.MAGIC_NUMBER);
    return f;
  } },
  { name: 'serial port left in cooked mode (ONLCR turns 0A into 0D 0A)', why: 'badCrc', transport: 'pty-master-cooked' },
  { name: 'garbage bytes between frames', why: 'skippedBytes', frames: (f) => [...f.slice(0, 3), Buffer.from([0x00, 0x55, 0xAA]), ...f.slice(3)] },
  { name: 'frame truncated at the end', why: 'pendingBytes', frames: (f) => [...f.slice(0, -1), f[f.length - 1].subarray(0, 20)] },
  { name: 'payload not zero-trimmed', why: 'zero-trimming', vpd: true, mutate: (l) => { const e = vpdOf(l, 2); e.msg.confidence = 0; e.raw = serializeUntrimmed(e); } },
  { name: 'payload longer than the message', why: 'zero-trimming', frames: (f, l) => {
    const e = l[0];
    const C = e.msg.constructor;
    const b = Buffer.alloc(f[0].length + 1);
    f[0].copy(b, 0, 0, f[0].length - 2);
    b[1] = f[0][1] + 1;
    b[b.length - 3] = 7;
    refreshCrc(b, C.MAGIC_NUMBER);
    f[0] = b;
    return f;
  } },
  { name: 'VPD expected but not sent', why: 'VISION_POSITION_DELTA message(s) for', check: ['--expect-vpd'] },
  { name: 'VPD sent but not expected', why: 'VISION_POSITION_DELTA not expected', vpd: true, check: customArg },
  { name: 'VPD position_delta in camera axes', why: 'position_delta[', vpd: true, mutate: (l) => { const e = vpdOf(l, 2); e.msg.positionDelta = e.info.tc.slice(); } },
  { name: 'VPD angle_delta sign flipped', why: 'angle_delta[', vpd: true, mutate: (l) => { const e = vpdOf(l, 2); e.msg.angleDelta = e.msg.angleDelta.map((v) => -v); } },
  { name: 'VPD time_delta_usec in ms', why: 'time_delta_usec =', vpd: true, mutate: (l) => { const e = vpdOf(l, 2); e.msg.timeDeltaUsec /= 1000n; } },
  { name: 'VPD for a failed row', why: 'VISION_POSITION_DELTA message(s) for', vpd: true, mutate: (l) => {
    const v = new ardupilotmega.VisionPositionDelta();
    v.timeUsec = rows[FAILED[0]].tCurrUs; v.timeDeltaUsec = rows[FAILED[0]].tCurrUs - rows[FAILED[0]].tPrevUs;
    v.angleDelta = [0, 0, 0]; v.positionDelta = [0, 0, 0]; v.confidence = 0;
    const i = l.indexOf(odoOf(l, FAILED[0]));
    l.splice(i + 1, 0, { msg: v, info: odoOf(l, FAILED[0]).info, sysid: 1, compid: 197 });
    return renumber(l);
  } },
  { name: 'extrinsic ignored (camera-axis velocity with custom extrinsic)', why: 'vx =', vpd: true, mutate: (l) => {
    const wrong = buildMessages(rows, { Rbc: DEFAULT_RBC, pbc: [0, 0, 0], vpd: true });
    return wrong;
  } },
  { name: 'lever arm ignored in velocity', why: ['vx =', 'vy =', 'vz ='], vpd: true, mutate: () => buildMessages(rows, { Rbc: CUSTOM_RBC, pbc: [0, 0, 0], vpd: true }) },
];

async function main() {
  let passed = 0, failed = 0;
  for (const c of cases) {
    if (ONLY && !c.name.includes(ONLY)) continue;
    const expectPass = c.expect === 'pass';
    let list = c.list || (c.vpd ? baseVpd() : base());
    const checkArgs = c.check || (c.vpd ? [...customArg, '--expect-vpd'] : []);
    if (c.mutate) { const r = c.mutate(list); if (Array.isArray(r)) list = r; }
    let frames = serialize(list);
    if (c.frames) frames = c.frames(frames, list);
    const count = list.filter((e) => e.msg instanceof common.Odometry).length;
    if (c.transport && c.transport !== 'udp' && spawnSync('python3', ['-c', 'import pty'], { encoding: 'utf8' }).status !== 0) {
      console.log(`SKIP  ${c.name} (no python3 to make a pty)`);
      continue;
    }
    const dec = await runDecoder(frames, { count, chunk: c.chunk, transport: c.transport || 'udp' });
    const chk = runCheck(dec.outFile, csv, checkArgs);
    let good;
    let detail = '';
    if (expectPass) {
      good = dec.code === 0 && chk.code === 0;
      if (!good) detail = `decode exit ${dec.code} ${dec.stderr.trim()}\n${chk.out}`;
    } else {
      const whys = [].concat(c.why);
      good = chk.code === 1 && whys.some((w) => chk.out.includes(w));
      if (!good) detail = `check exit ${chk.code} (want 1), looked for '${c.why}'\n${chk.out}`;
    }
    if (good) passed++; else failed++;
    const last = chk.out.trim().split('\n').filter((s) => s.startsWith('MISMATCH')).slice(0, 1).join('');
    console.log(`${good ? 'ok  ' : 'FAIL'}  ${expectPass ? 'accepts' : 'rejects'}: ${c.name}${!expectPass && good ? `  [${last.slice(9, 150)}]` : ''}`);
    if (!good) console.log(detail.split('\n').map((s) => `      ${s}`).join('\n'));
  }
  if (!KEEP) fs.rmSync(TMP, { recursive: true, force: true });
  else console.log(`kept ${TMP}`);
  console.log(`\n${passed} passed, ${failed} failed`);
  process.exit(failed ? 1 : 0);
}

main();
