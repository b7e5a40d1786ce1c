#!/usr/bin/env node
// autopilot_sim.mjs — a simulated PX4 autopilot talking to rgbd-odometry over its real link.
//
// Built on node-mavlink (framing, CRC, field coding), nothing of the project's code. It does
// what PX4's MAVLink module does on an Onboard-mode port: a HEARTBEAT at 1 Hz as PX4
// (MAV_AUTOPILOT_PX4 = 12, MAV_TYPE_QUADROTOR, system 1 component 1), TIMESYNC requests at
// 10 Hz, and PX4's timesync offset estimator run on the answers (reimplemented below from its
// published description, src/lib/timesync in PX4-Autopilot: a sample's offset is
// (ts1 + now - 2 tc1) / 2 in our (the autopilot's) clock, samples with a round trip of 10 ms or
// more are not used, double exponential smoothing whose gains move from 0.05 to 0.003 along a
// sigmoid over the first 500 samples, converged after 500 samples, reset after more than 5
// samples in a row 100 ms off a converged estimate). It also answers the program's own
// TIMESYNC requests as PX4 does (tc1 = its clock in ns, ts1 echoed, target = the requester).
//
// The truth: the program's clock is CLOCK_MONOTONIC (std::chrono::steady_clock on Linux) and so
// is process.hrtime.bigint(); this autopilot's clock is that plus --offset-ns (default
// 1234.567 s), so the offset PX4's estimator must find is exactly --offset-ns. Every answer is
// also checked for causality: the program's tc1 lies between our request and its answer, and
// with --expect-converged the converged offset must lie within what the used round trips allow
// (offsetBoundUs: the filter's weights times half of each round trip), not within a fixed time:
// a loaded machine lengthens the round trips; a stamp from another clock or instant does not fit.
//
// Unkind link, on request: --loss drops a fraction of our frames, --reorder swaps some
// neighbours, --garbage puts noise, corrupted and truncated frames, unknown messages, MAVLink 1
// heartbeats and signed frames between the real ones.
//
// Everything the program sends is written unchanged to --capture (for decode.mjs --file and
// check.mjs) and a JSON summary to --result.
//
// Usage:
//   node autopilot_sim.mjs (--udp-listen PORT | --udp-send HOST:PORT | --fd N) --result FILE
//       [--capture FILE] [--ready-file FILE] [--offset-ns N] [--timesync-hz 10] [--loss P]
//       [--reorder P] [--garbage P] [--seed N] [--start-after-ms T] [--converged-file FILE]
//       [--expect-converged] [--silent-after-answers N] [--silent-for-heartbeats N]
//       [--exit-after-heartbeats N] [--idle-exit-ms T] [--max-ms T] [--ardupilot]
//       [--attitude ROLL,PITCH | --attitude none]
//   --udp-listen PORT   the program sends to us (udp://127.0.0.1:PORT); we answer the address
//                       its datagrams come from, from the moment the first one arrives
//   --udp-send H:P      the program listens (udpin://H:P); we speak first
//   --fd N              an inherited fd: the master of the pty whose slave the program opened.
//                       We speak only after the program's first bytes (until it opened the
//                       port and set it raw, the pty's echo would send our frames back)
//   --silent-after-answers N   go quiet (a vanished autopilot) after N answers to our requests,
//   --silent-for-heartbeats N  for as long as the program sends N heartbeats, then speak again
//   --exit-after-heartbeats N  with the above: exit after N more program heartbeats
//   --idle-exit-ms T    exit once the program has sent nothing for T ms (default 3000)
//   --attitude R,P      ATTITUDE streamed at 10 Hz with this roll and pitch [rad] (default
//                       0.0312,-0.0187; none: not streamed)
//   --ardupilot         HEARTBEAT as ArduPilot (MAV_AUTOPILOT_ARDUPILOTMEGA); the EKF origin the
//                       program sends (SET_GPS_GLOBAL_ORIGIN, SET_HOME_POSITION) goes to the result
//   --gyro-groundtruth F   ATTITUDE's rates are the body rates (FRD, the camera mounted as an all-zero
//                       body: configuration assumes) of this TUM groundtruth.txt, as make_imu.py
//                       makes them, with --gyro-bias bx,by,bz and --gyro-noise rad/s, at the
//                       instant of the recording the virtual sensor is playing: --gyro-clock-file
//                       is the file it writes (RGBDO_VIRTUAL_SENSOR_CLOCK_FILE); until it exists
//                       the rates are zero. --gyro-delay-ms D stamps them D ms late (a filtered or
//                       late-stamped gyro). The streams' rate is what MAV_CMD_SET_MESSAGE_INTERVAL asks.
// Exit status: 0 all assertions held, 1 some did not (see the result's "failures"), 64 usage.

import dgram from 'node:dgram';
import fs from 'node:fs';
import tty from 'node:tty';
import {
  MavLinkPacketSplitter, MavLinkPacketParser, MavLinkProtocolV1, MavLinkProtocolV2, MavLinkPacketSignature,
  minimal, common, ardupilotmega,
} from 'node-mavlink';

const SYSID = 1;
const COMPID = 1;  // MAV_COMP_ID_AUTOPILOT1
const MAV_AUTOPILOT_PX4 = 12;
const MAV_AUTOPILOT_ARDUPILOTMEGA = 3;
const MAV_TYPE_QUADROTOR = 2;

// PX4 timesync constants (published in src/lib/timesync/Timesync.hpp).
const PX4 = {
  alphaInitial: 0.05, betaInitial: 0.05, alphaFinal: 0.003, betaFinal: 0.003,
  convergenceWindow: 500, maxRttUs: 10_000, maxDeviationUs: 100_000, maxConsecutiveHighDeviation: 5,
};

function usage(msg) {
  process.stderr.write(`autopilot_sim.mjs: ${msg}\n(see the header of this file for usage)\n`);
  process.exit(64);
}

function parseArgs(argv) {
  const o = {
    offsetNs: 1_234_567_000_000n, timesyncHz: 10, loss: 0, reorder: 0, garbage: 0, seed: 1, startAfterMs: 0,
    expectConverged: false, attitude: [0.0312, -0.0187], silentAfterAnswers: null, silentForHeartbeats: 3, exitAfterHeartbeats: null,
    idleExitMs: 3000, maxMs: 300_000, gyroDelayMs: 0, gyroBias: [0.010, -0.006, 0.008], gyroNoise: 0.005,
  };
  const num = (a, v) => { if (v === undefined || !/^-?\d+(\.\d+)?$/.test(v)) usage(`${a} needs a number`); return Number(v); };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const next = () => { if (i + 1 >= argv.length) usage(`${a} needs a value`); return argv[++i]; };
    switch (a) {
      case '--udp-listen': o.udpListen = num(a, next()); break;
      case '--udp-send': { const v = next(); const c = v.lastIndexOf(':'); o.udpSend = { host: v.slice(0, c), port: num(a, v.slice(c + 1)) }; break; }
      case '--fd': o.fd = num(a, next()); break;
      case '--result': o.result = next(); break;
      case '--capture': o.capture = next(); break;
      case '--ready-file': o.readyFile = next(); break;
      case '--converged-file': o.convergedFile = next(); break;
      case '--offset-ns': o.offsetNs = BigInt(next()); break;
      case '--timesync-hz': o.timesyncHz = num(a, next()); break;
      case '--loss': o.loss = num(a, next()); break;
      case '--reorder': o.reorder = num(a, next()); break;
      case '--garbage': o.garbage = num(a, next()); break;
      case '--seed': o.seed = num(a, next()); break;
      case '--start-after-ms': o.startAfterMs = num(a, next()); break;
      case '--expect-converged': o.expectConverged = true; break;
      case '--silent-after-answers': o.silentAfterAnswers = num(a, next()); break;
      case '--silent-for-heartbeats': o.silentForHeartbeats = num(a, next()); break;
      case '--exit-after-heartbeats': o.exitAfterHeartbeats = num(a, next()); break;
      case '--idle-exit-ms': o.idleExitMs = num(a, next()); break;
      case '--max-ms': o.maxMs = num(a, next()); break;
      case '--ardupilot': o.ardupilot = true; break;
      case '--attitude': { const v = next(); o.attitude = v === 'none' ? null : v.split(',').map(Number); break; }
      case '--gyro-groundtruth': o.gyroGroundtruth = next(); break;
      case '--gyro-clock-file': o.gyroClockFile = next(); break;
      case '--gyro-delay-ms': o.gyroDelayMs = num(a, next()); break;
      case '--gyro-bias': o.gyroBias = next().split(',').map(Number); break;
      case '--gyro-noise': o.gyroNoise = num(a, next()); break;
      default: usage(`unknown argument '${a}'`);
    }
  }
  if ([o.udpListen, o.udpSend, o.fd].filter((x) => x !== undefined).length !== 1) usage('give one of --udp-listen, --udp-send, --fd');
  if (!o.result) usage('--result is required');
  return o;
}

// The body rate (rad/s, FRD; x_body = z_camera, y_body = x_camera, z_body = y_camera) of a TUM
// groundtruth.txt at time t (s), as make_imu.py (../shared/tools/imu-from-groundtruth) makes it:
// the relative rotation of the poses slerped 5 ms either side, over 10 ms. Null outside it.
function groundTruthGyro(path) {
  const G = fs.readFileSync(path, 'utf8').split('\n').filter((l) => l && !l.startsWith('#'))
    .map((l) => l.trim().split(/\s+/).map(Number)).filter((p) => p.length >= 8).map((p) => [p[0], p.slice(4, 8)])
    .sort((a, b) => a[0] - b[0]);
  const R = ([x, y, z, w]) => {
    const n = Math.hypot(x, y, z, w); x /= n; y /= n; z /= n; w /= n;
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
      [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
      [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]];
  };
  const slerp = (q0, q1, a) => {
    let d = q0.reduce((s, v, i) => s + v * q1[i], 0);
    if (d < 0) { q1 = q1.map((v) => -v); d = -d; }
    let q;
    if (d > 0.9995) q = q0.map((v, i) => v + a * (q1[i] - v));
    else { const th = Math.acos(d), s = Math.sin(th); q = q0.map((v, i) => (Math.sin((1 - a) * th) * v + Math.sin(a * th) * q1[i]) / s); }
    const n = Math.hypot(...q); return q.map((v) => v / n);
  };
  const at = (t) => {
    let lo = 0, hi = G.length - 1;
    if (t < G[0][0] || t >= G[hi][0]) return null;
    while (hi - lo > 1) { const m = (lo + hi) >> 1; if (G[m][0] <= t) lo = m; else hi = m; }
    const [t0, q0] = G[lo], [t1, q1] = G[hi];
    return slerp(q0, q1, t1 > t0 ? (t - t0) / (t1 - t0) : 0);
  };
  const h = 0.005;
  return (t) => {
    const qa = at(t - h), qb = at(t + h);
    if (!qa || !qb) return null;
    const A = R(qa), B = R(qb);
    const M = [0, 1, 2].map((i) => [0, 1, 2].map((j) => A[0][i] * B[0][j] + A[1][i] * B[1][j] + A[2][i] * B[2][j]));
    const c = Math.max(-1, Math.min(1, (M[0][0] + M[1][1] + M[2][2] - 1) / 2)), th = Math.acos(c);
    const k = th < 1e-9 ? 0.5 : th / (2 * Math.sin(th));
    const wc = [M[2][1] - M[1][2], M[0][2] - M[2][0], M[1][0] - M[0][1]].map((v) => k * v / (2 * h));
    return [wc[2], wc[0], wc[1]];
  };
}

// A small deterministic PRNG (mulberry32), so a run's unkindness can be replayed.
function rng(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6D2B79F5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

const monotonicNs = () => process.hrtime.bigint();

// PX4's estimator, from its description (not its code).
class Px4TimesyncEstimator {
  constructor() { this.reset(); this.highRttCount = 0; }
  reset() {
    this.sequence = 0; this.offsetUs = 0; this.skewUs = 0; this.weights = [];
    this.alpha = PX4.alphaInitial; this.beta = PX4.betaInitial; this.highDeviationCount = 0; this.resets = (this.resets ?? -1) + 1;
  }
  converged() { return this.sequence >= PX4.convergenceWindow; }
  // nowUs: our clock at arrival; tc1Ns: the program's clock at answering; ts1Ns: ours at asking.
  update(nowUs, tc1Ns, ts1Ns) {
    const ts1Us = Number(ts1Ns / 1000n), tc1Us = Number(tc1Ns / 1000n);
    const sampleUs = (ts1Us + nowUs - 2 * tc1Us) / 2;
    const rttUs = nowUs - ts1Us;
    if (rttUs >= PX4.maxRttUs) { this.highRttCount++; return 'rtt'; }
    if (this.converged() && Math.abs(this.offsetUs - sampleUs) > PX4.maxDeviationUs) {
      if (++this.highDeviationCount > PX4.maxConsecutiveHighDeviation) this.reset();
      return 'deviation';
    }
    if (!this.converged()) {
      // Gains slide from the initial to the final values along 1 - exp(0.5 (1 - 1/(1 - progress))).
      const progress = this.sequence / PX4.convergenceWindow;
      const p = 1 - Math.exp(0.5 * (1 - 1 / (1 - progress)));
      this.alpha = p * PX4.alphaFinal + (1 - p) * PX4.alphaInitial;
      this.beta = p * PX4.betaFinal + (1 - p) * PX4.betaInitial;
    } else {
      this.alpha = PX4.alphaFinal;
      this.beta = PX4.betaFinal;
    }
    if (this.sequence === 0) {
      this.offsetUs = sampleUs;
    } else {
      const previous = this.offsetUs;
      this.offsetUs = this.alpha * sampleUs + (1 - this.alpha) * (this.offsetUs + this.skewUs);
      this.skewUs = this.beta * (this.offsetUs - previous) + (1 - this.beta) * this.skewUs;
    }
    this.trackWeights(rttUs);
    this.sequence++;
    this.highDeviationCount = 0;
    return 'used';
  }
  // The filter is linear in its samples: the offset is sum(o_i * sample_i), the skew
  // sum(k_i * sample_i), with weights that follow the same recursion as the state.
  trackWeights(rttUs) {
    if (this.sequence === 0) {
      this.weights.push({ o: 1, k: 0, rttUs });
      return;
    }
    for (const w of this.weights) {
      const o = (1 - this.alpha) * (w.o + w.k);
      w.k = this.beta * (o - w.o) + (1 - this.beta) * w.k;
      w.o = o;
    }
    this.weights.push({ o: this.alpha, k: this.beta * this.alpha, rttUs });
  }
  // How far the offset can be from the truth when every answer was stamped between its request
  // and its arrival: each sample is then within half its round trip (+1 us of our rounding to
  // whole microseconds), and the offset within the weighted sum of those. Load on either side
  // lengthens round trips and loosens this; a wrong clock or a stamp outside the exchange does not fit.
  errorBoundUs() { return this.weights.reduce((sum, w) => sum + Math.abs(w.o) * (w.rttUs / 2 + 1), 0); }
}

function main() {
  const opt = parseArgs(process.argv.slice(2));
  const random = rng(opt.seed);
  const t0 = monotonicNs();
  const ourNowNs = () => monotonicNs() + opt.offsetNs;  // this autopilot's clock
  const truthUs = Number(opt.offsetNs) / 1000;  // autopilot clock - program clock

  const r = {
    mode: opt.udpListen !== undefined ? 'udp-listen' : opt.udpSend ? 'udp-send' : 'pty',
    trueOffsetUs: truthUs, heartbeatsSent: 0, requestsSent: 0, answersReceived: 0, answersUsed: 0,
    answersRttRejected: 0, answersNotOurs: 0, causalityViolations: 0, ourAnswersToProgram: 0,
    programHeartbeats: 0, programRequests: 0, odometry: 0, framesFromProgram: 0, badFromProgram: 0,
    origins: [], homePositions: [], visionPositionDelta: 0, attitudeSent: 0, intervalRequests: [], gyroSamples: 0,
    rules: { staleFused: 0, notAfterPrevious: 0, deltaDropped: 0, beforeOrigin: 0 },
    framesDropped: 0, framesReordered: 0, garbageBytes: 0, startByteNoise: 0, requestsDelivered: 0,
    requestsDeliveredWhileHeard: 0, corruptFrames: 0, unknownFrames: 0, v1Frames: 0,
    signedFrames: 0, silentPeriods: 0, converged: false, convergedAfterSamples: null, offsetUs: null,
    offsetErrorUs: null, offsetBoundUs: null, minRttUs: null, maxUsedRttUs: null, odometryLatencyUs: null, failures: [],
  };
  const estimator = new Px4TimesyncEstimator();
  let lastOdometryUs = null, lastDeltaUs = null;
  const outstanding = new Map();  // ts1 (string) -> true: our requests not answered yet
  const requestTimes = [];  // when each request that went out was sent (our monotonic clock)
  const odometryStamps = [];  // [time_usec (program clock), arrival (our clock, us)]
  const capture = opt.capture ? fs.openSync(opt.capture, 'w') : null;

  // ---- transport ----
  let writeBytes = () => {};
  let peerKnown = false;
  let closeTransport = () => {};
  let lastRxNs = null;
  let talking = false;  // we have started speaking

  const protocol = new MavLinkProtocolV2(SYSID, COMPID);
  const protocolV1 = new MavLinkProtocolV1(SYSID, COMPID);
  let seq = 0;
  const frame = (msg, proto = protocol) => proto.serialize(msg, seq++ & 0xFF);

  // ---- unkind link ----
  let held = null;  // a frame held back to be sent after the next one
  function noise() {
    const parts = [];
    const kind = random();
    if (kind < 0.15) {  // noise of every byte value: start bytes, false headers with any length and id
      const n = 1 + Math.floor(random() * 40);
      const b = Buffer.alloc(n);
      for (let i = 0; i < n; i++) b[i] = Math.floor(random() * 256);
      if (random() < 0.5) b[Math.floor(random() * n)] = random() < 0.5 ? 0xFD : 0xFE;  // a false start for sure
      r.garbageBytes += n; r.startByteNoise++; parts.push(b);
    } else if (kind < 0.3) {  // plain noise, no start bytes
      const n = 1 + Math.floor(random() * 40);
      const b = Buffer.alloc(n);
      for (let i = 0; i < n; i++) { let v = Math.floor(random() * 256); if (v === 0xFD || v === 0xFE) v = 0x55; b[i] = v; }
      r.garbageBytes += n; parts.push(b);
    } else if (kind < 0.5) {  // a heartbeat with a flipped payload bit (bad checksum)
      const b = Buffer.from(frame(heartbeat()));
      b[10 + Math.floor(random() * 9)] ^= 1 << Math.floor(random() * 8);
      r.corruptFrames++; parts.push(b);
    } else if (kind < 0.65) {  // a frame cut short: what follows it must still be found
      const b = frame(heartbeat());
      r.corruptFrames++; parts.push(b.subarray(0, 3 + Math.floor(random() * (b.length - 4))));
    } else if (kind < 0.8) {  // a message the program does not read (SCALED_PRESSURE)
      const m = new common.ScaledPressure();
      m.timeBootMs = Number((ourNowNs() / 1_000_000n) & 0xFFFFFFFFn); m.pressAbs = 1013 + random(); m.temperature = 2000;
      r.unknownFrames++; parts.push(frame(m));
    } else if (kind < 0.9) {  // MAVLink 1 heartbeat, as on a port left at MAVLink 1
      r.v1Frames++; parts.push(frame(heartbeat(), protocolV1));
    } else {  // a signed heartbeat (signature not checkable without the key: skipped whole)
      const key = MavLinkPacketSignature.key('autopilot-sim');
      const p = new MavLinkProtocolV2(SYSID, COMPID, MavLinkProtocolV2.IFLAG_SIGNED);
      r.signedFrames++; parts.push(p.sign(p.serialize(heartbeat(), seq++ & 0xFF), 1, key));
    }
    return parts;
  }
  function send(buf) {  // true when it goes out (now, or held back to follow the next)
    if (!peerKnown) return false;
    if (random() < opt.loss) { r.framesDropped++; return false; }
    const out = [];
    if (random() < opt.garbage) out.push(...noise());
    if (held) { out.push(buf, held); held = null; r.framesReordered++; }
    else if (random() < opt.reorder) { held = buf; }
    else out.push(buf);
    for (const b of out) writeBytes(b);
    return true;
  }

  function heartbeat() {
    const m = new minimal.Heartbeat();
    m.type = MAV_TYPE_QUADROTOR; m.autopilot = opt.ardupilot ? MAV_AUTOPILOT_ARDUPILOTMEGA : MAV_AUTOPILOT_PX4;
    m.baseMode = 0x51; m.customMode = 0x10000;
    m.systemStatus = 4; m.mavlinkVersion = 3;
    return m;
  }

  // ---- what the program sends ----
  const splitter = new MavLinkPacketSplitter({}, { onCrcError: () => { r.badFromProgram++; } });
  const parser = new MavLinkPacketParser();
  splitter.pipe(parser);
  let silentUntilHeartbeats = null;  // program heartbeat count at which we speak again
  let exitAtHeartbeats = null;

  parser.on('data', (packet) => {
    const arrivalNs = ourNowNs();
    const arrivalUs = Number(arrivalNs / 1000n);
    r.framesFromProgram++;
    const id = packet.header.msgid;
    if (id === minimal.Heartbeat.MSG_ID) {
      r.programHeartbeats++;
      if (silentUntilHeartbeats !== null && r.programHeartbeats >= silentUntilHeartbeats) {
        silentUntilHeartbeats = null;  // back
        if (opt.exitAfterHeartbeats !== null) exitAtHeartbeats = r.programHeartbeats + opt.exitAfterHeartbeats;
      }
      if (exitAtHeartbeats !== null && r.programHeartbeats >= exitAtHeartbeats) finish('heartbeats');
    } else if (id === common.TimeSync.MSG_ID) {
      const m = packet.protocol.data(packet.payload, common.TimeSync);
      if (m.tc1 === 0n) {  // the program asks our time: answer as PX4 does
        r.programRequests++;
        if (silentUntilHeartbeats === null) {
          const a = new common.TimeSync();
          a.tc1 = ourNowNs(); a.ts1 = m.ts1; a.targetSystem = packet.header.sysid; a.targetComponent = packet.header.compid;
          r.ourAnswersToProgram++;
          send(frame(a));
        }
      } else {
        r.answersReceived++;
        if (m.targetSystem !== SYSID || m.targetComponent !== COMPID || !outstanding.has(m.ts1.toString())) {
          r.answersNotOurs++;
          return;
        }
        outstanding.delete(m.ts1.toString());
        // Causality, exactly: the program answered after we asked and before we heard it.
        const askedProgramNs = m.ts1 - opt.offsetNs, heardProgramNs = arrivalNs - opt.offsetNs;
        if (m.tc1 < askedProgramNs || m.tc1 > heardProgramNs) r.causalityViolations++;
        const rttUs = Number((arrivalNs - m.ts1) / 1000n);
        r.minRttUs = r.minRttUs === null ? rttUs : Math.min(r.minRttUs, rttUs);
        const verdict = estimator.update(arrivalUs, m.tc1, m.ts1);
        if (verdict === 'used') { r.answersUsed++; r.maxUsedRttUs = Math.max(r.maxUsedRttUs ?? 0, rttUs); }
        if (verdict === 'rtt') r.answersRttRejected++;
        if (estimator.converged() && !r.converged) {
          r.converged = true;
          r.convergedAfterSamples = estimator.sequence;
          if (opt.convergedFile) fs.writeFileSync(opt.convergedFile, `${estimator.offsetUs}\n`);
        }
        // Only the answer that makes the count: a later one not used (a slow program's answer
        // to a request sent before we went quiet, rejected for its round trip) leaves the count
        // where it was and must not start a second silence.
        if (opt.silentAfterAnswers !== null && verdict === 'used' && r.answersUsed === opt.silentAfterAnswers) {
          silentUntilHeartbeats = r.programHeartbeats + opt.silentForHeartbeats;  // vanish for a while
          r.silentPeriods++;
        }
      }
    } else if (id === common.Odometry.MSG_ID) {
      const m = packet.protocol.data(packet.payload, common.Odometry);
      r.odometry++;
      odometryStamps.push([Number(m.timeUsec), arrivalUs]);
      // The autopilots' acceptance rules, as their source states them:
      // PX4 ev_control.cpp: quality_sufficient = (EKF2_EV_QMIN <= 0) || (quality >= EKF2_EV_QMIN),
      // default 0; ev_pos_control.cpp fuses a position that is finite (PX4_ISFINITE(pos(0))).
      // So a failed pair's message (quality -1) with a finite position is fused: a stale pose.
      if (m.quality === -1 && Number.isFinite(m.x) && Number.isFinite(m.y)) r.rules.staleFused++;
      // EKF2's and EKF3's sample buffers keep time order: a sample not after the last one is
      // a duplicate (or out of order) fused at the wrong time.
      if (lastOdometryUs !== null && m.timeUsec <= lastOdometryUs) r.rules.notAfterPrevious++;
      lastOdometryUs = m.timeUsec;
      // EKF3 needs an origin (SET_GPS_GLOBAL_ORIGIN) to use an external position without GPS.
      if (opt.ardupilot && r.origins.length === 0) r.rules.beforeOrigin++;
    } else if (id === common.CommandLong.MSG_ID) {
      // MAV_CMD_SET_MESSAGE_INTERVAL, as PX4 and ArduPilot take it: the message streamed at
      // the interval asked for, COMMAND_ACK ACCEPTED to the sender.
      const m = packet.protocol.data(packet.payload, common.CommandLong);
      r.intervalRequests.push({ command: m.command, messageId: m._param1, intervalUs: m._param2, confirmation: m.confirmation,
        targetSystem: m.targetSystem, targetComponent: m.targetComponent });
      if (m.command === 511 && silentUntilHeartbeats === null) {
        const ack = new common.CommandAck();
        ack.command = 511; ack.result = 0; ack.targetSystem = packet.header.sysid; ack.targetComponent = packet.header.compid;
        send(frame(ack));
        if (m._param1 === common.Attitude.MSG_ID && m._param2 > 0) streamAttitude(m._param2 / 1000);
      }
    } else if (id === common.SetGpsGlobalOrigin.MSG_ID || id === common.SetHomePosition.MSG_ID) {
      // The EKF origin (ArduPilot needs one to use an external position without GPS).
      const home = id === common.SetHomePosition.MSG_ID;
      const m = packet.protocol.data(packet.payload, home ? common.SetHomePosition : common.SetGpsGlobalOrigin);
      (home ? r.homePositions : r.origins).push({ latitude: m.latitude, longitude: m.longitude, altitude: m.altitude, targetSystem: m.targetSystem });
    } else if (id === 11011) {
      r.visionPositionDelta++;
      // EKF3 drops body odometry less than sensorIntervalMin_ms (50 ms) after the last
      // (AP_NavEKF3_Measurements.cpp writeBodyFrameOdom): a motion lost.
      const t = packet.protocol.data(packet.payload, ardupilotmega.VisionPositionDelta).timeUsec;
      if (lastDeltaUs !== null && t - lastDeltaUs < 50_000n) r.rules.deltaDropped++;
      lastDeltaUs = t;
    }
  });

  function fromProgram(chunk) {
    lastRxNs = monotonicNs();
    if (capture) fs.writeSync(capture, chunk);
    splitter.write(chunk);
    if (!talking && opt.udpSend === undefined) startTalking();  // PX4 answers whoever talks to it
  }

  // ---- the gyro, from ground truth ----
  const gyro = opt.gyroGroundtruth ? groundTruthGyro(opt.gyroGroundtruth) : null;
  let gyroClock = null;  // [start ns (our clock), the recording's time then (ns), pass ns]
  const gyroNormal = () => { const u = Math.max(random(), 1e-12), v = random(); return Math.sqrt(-2 * Math.log(u)) * Math.cos(2 * Math.PI * v); };
  function gyroRates(nowNs) {
    if (!gyro) return null;
    if (!gyroClock && opt.gyroClockFile && fs.existsSync(opt.gyroClockFile)) {
      const f = fs.readFileSync(opt.gyroClockFile, 'utf8').trim().split(/\s+/).map((x) => BigInt(x));
      if (f.length === 3) gyroClock = f;
    }
    if (!gyroClock) return [0, 0, 0];
    const [start, recorded, pass] = gyroClock;
    let sinceNs = Number(nowNs - start);
    if (pass > 0n) sinceNs = ((sinceNs % Number(pass)) + Number(pass)) % Number(pass);
    const w = gyro(Number(recorded) * 1e-9 + sinceNs * 1e-9);
    if (!w) return [0, 0, 0];
    r.gyroSamples++;
    return w.map((x, k) => x + opt.gyroBias[k] + opt.gyroNoise * gyroNormal());
  }

  // ---- our streams ----
  let timers = [];
  let attitudeTimer = null, attitudeFn = null;
  function streamAttitude(periodMs) {  // at the rate the program asked for
    if (!attitudeFn) return;
    if (attitudeTimer) { clearInterval(attitudeTimer); timers = timers.filter((t) => t !== attitudeTimer); }
    attitudeTimer = setInterval(attitudeFn, periodMs); timers.push(attitudeTimer);
    r.attitudePeriodMs = periodMs;
  }
  function startTalking() {
    talking = true;
    const beat = () => {
      if (silentUntilHeartbeats !== null) return;
      r.heartbeatsSent++; send(frame(heartbeat()));
    };
    const ask = () => {
      if (silentUntilHeartbeats !== null) return;
      const m = new common.TimeSync();
      m.tc1 = 0n; m.ts1 = ourNowNs(); m.targetSystem = 0; m.targetComponent = 0;
      outstanding.set(m.ts1.toString(), true);
      if (outstanding.size > 1000) outstanding.delete(outstanding.keys().next().value);
      r.requestsSent++;
      if (send(frame(m))) requestTimes.push(monotonicNs());
    };
    // ATTITUDE at 10 Hz, as PX4 streams it on an Onboard port: the program levels its local
    // frame with the roll and pitch it holds at the first pair.
    const attitude = () => {
      if (silentUntilHeartbeats !== null) return;
      const m = new common.Attitude();
      const nowNs = monotonicNs();
      // Stamped when sent (ArduPilot) or published (PX4): --gyro-delay-ms later than measured.
      m.timeBootMs = Number(((nowNs + opt.offsetNs + BigInt(Math.round(opt.gyroDelayMs * 1e6))) / 1_000_000n) & 0xFFFFFFFFn);
      [m.roll, m.pitch] = opt.attitude; m.yaw = 1.2;
      const w = gyroRates(nowNs);
      if (w) [m.rollspeed, m.pitchspeed, m.yawspeed] = w;
      r.attitudeSent++; send(frame(m));
    };
    attitudeFn = opt.attitude ? attitude : null;
    beat();
    timers.push(setInterval(beat, 1000));
    if (opt.attitude) { attitude(); attitudeTimer = setInterval(attitude, 100); timers.push(attitudeTimer); }
    if (opt.timesyncHz > 0) timers.push(setInterval(ask, 1000 / opt.timesyncHz));
  }

  // ---- finishing ----
  let finished = false;
  function finish(reason) {
    if (finished) return;
    finished = true;
    for (const t of timers) clearInterval(t);
    r.stopReason = reason;
    r.seconds = Number(monotonicNs() - t0) / 1e9;
    r.sequence = estimator.sequence;
    r.filterResets = estimator.resets;
    r.highRttCount = estimator.highRttCount;
    r.offsetUs = estimator.sequence > 0 ? estimator.offsetUs : null;
    r.offsetErrorUs = r.offsetUs === null ? null : r.offsetUs - truthUs;
    r.offsetBoundUs = r.offsetUs === null ? null : estimator.errorBoundUs();
    // The requests the program could answer: delivered while it was still sending, at least
    // a second before its last frame (what it answers is the share of these; under
    // ThreadSanitizer an answer can take a few hundred milliseconds).
    r.requestsDelivered = requestTimes.length;
    if (lastRxNs !== null) r.requestsDeliveredWhileHeard = requestTimes.filter((t) => t < lastRxNs - 1_000_000_000n).length;
    if (r.converged && odometryStamps.length) {
      // What PX4's sync_stamp() makes of each ODOMETRY time_usec once converged: our clock
      // at capture; it must come before the message reached us.
      const lat = odometryStamps.map(([t, arrival]) => arrival - (t + estimator.offsetUs));
      r.odometryLatencyUs = { min: Math.min(...lat), max: Math.max(...lat) };
    }
    if (r.causalityViolations > 0) r.failures.push(`${r.causalityViolations} answers outside [request, arrival]`);
    if (r.badFromProgram > 0) r.failures.push(`${r.badFromProgram} frames from the program failed their CRC`);
    if (r.answersNotOurs > 0) r.failures.push(`${r.answersNotOurs} answers not to our requests`);
    if (r.rules.staleFused) r.failures.push(`${r.rules.staleFused} failed pairs with a finite pose: PX4 (EKF2_EV_QMIN 0) fuses them`);
    if (r.rules.notAfterPrevious) r.failures.push(`${r.rules.notAfterPrevious} ODOMETRY not after the previous one`);
    if (r.rules.deltaDropped) r.failures.push(`${r.rules.deltaDropped} VISION_POSITION_DELTA within 50 ms of the last: EKF3 drops them`);
    if (r.odometry > 0 && r.visionPositionDelta > 0) r.failures.push('ODOMETRY and VISION_POSITION_DELTA both: EKF3 fuses the motion twice');
    if (opt.expectConverged) {
      if (!r.converged) r.failures.push(`not converged: ${estimator.sequence} of ${PX4.convergenceWindow} samples`);
      else if (Math.abs(r.offsetErrorUs) > r.offsetBoundUs) {
        r.failures.push(`offset off by ${r.offsetErrorUs} us, more than its round trips allow (${r.offsetBoundUs} us)`);
      }
    }
    fs.writeFileSync(opt.result, JSON.stringify(r, null, 1) + '\n');
    if (capture) fs.closeSync(capture);
    try { closeTransport(); } catch { /* closed */ }
    process.exit(r.failures.length ? 1 : 0);
  }
  setTimeout(() => finish('max-time'), opt.maxMs).unref();
  setInterval(() => {
    if (lastRxNs !== null && Number(monotonicNs() - lastRxNs) / 1e6 > opt.idleExitMs) finish('idle');
  }, 100);

  const announce = (what) => {
    if (opt.readyFile) {
      const tmp = `${opt.readyFile}.tmp${process.pid}`;
      fs.writeFileSync(tmp, `READY ${what}\n`);
      fs.renameSync(tmp, opt.readyFile);
    }
    process.stderr.write(`READY ${what}\n`);
  };

  if (opt.udpListen !== undefined || opt.udpSend) {
    const sock = dgram.createSocket({ type: 'udp4', recvBufferSize: 8 << 20 });
    let peer = opt.udpSend ? { address: opt.udpSend.host, port: opt.udpSend.port } : null;
    peerKnown = peer !== null;
    writeBytes = (b) => sock.send(b, peer.port, peer.address);
    sock.on('error', () => { /* a refused datagram before the program listens: keep going */ });
    sock.on('message', (msg, rinfo) => {
      if (opt.udpListen !== undefined) { peer = { address: rinfo.address, port: rinfo.port }; peerKnown = true; }
      fromProgram(msg);
    });
    closeTransport = () => sock.close();
    sock.bind(opt.udpListen ?? 0, '127.0.0.1', () => {
      announce(`udp 127.0.0.1:${sock.address().port}`);
      if (opt.udpSend) setTimeout(startTalking, opt.startAfterMs);
    });
  } else {
    const fd = opt.fd;
    peerKnown = true;
    writeBytes = (b) => {
      try { fs.writeSync(fd, b); } catch (e) { if (e.code !== 'EAGAIN') throw e; r.framesDropped++; }
    };
    // A tty stream reads without blocking a thread-pool thread (which would hold up the exit).
    const stream = tty.isatty(fd) ? new tty.ReadStream(fd) : fs.createReadStream(null, { fd, autoClose: false });
    stream.on('data', fromProgram);
    stream.on('error', () => finish('eof'));  // EIO once the program closed its side
    stream.on('end', () => finish('eof'));
    closeTransport = () => stream.destroy();
    announce(`fd ${fd}`);
  }
}

main();
