#!/usr/bin/env node
// decode.mjs — receive MAVLink frames and print every one of them as a JSON line.
//
// Independent of the project's own encoder: framing, CRC checking and field decoding are done
// by the npm package node-mavlink (MavLinkPacketSplitter -> MavLinkPacketParser ->
// protocol.data(payload, clazz)) with the message definitions of minimal, common and
// ardupilotmega. Nothing is hidden: frames that node-mavlink's splitter drops (bad CRC, message
// id without a known CRC_EXTRA) are reported as lines of their own, in stream order, and counted
// in the summary, as are bytes skipped between frames and an unfinished frame left at the end.
//
// Usage:
//   node decode.mjs (--udp PORT | --serial PATH | --fd N | --file PATH) [--bind ADDR] [--count N]
//                   [--timeout-ms T] [--start-timeout-ms T] [--max-ms T] [--linger-ms T]
//                   [--raw | --no-raw] [--out FILE] [--ready-file FILE]
//
//   --udp PORT          bind ADDR:PORT (ADDR default 127.0.0.1; PORT 0 = any free port; the
//                       READY line tells which one)
//   --serial PATH       a tty (pty slave, /dev/ttyUSB0, ...): opened without becoming the
//                       controlling tty and put in raw mode (`stty raw -echo`: no echo, no CR/LF
//                       translation, no signal or flow-control characters) before READY is
//                       announced, unless --no-raw. Use this when the bytes are written into the
//                       other end of the pty (the master) or arrive on a real serial line.
//   --fd N              read an inherited file descriptor: a pipe, or the MASTER of a pty whose
//                       slave the program under test opened as its serial port. Its tty modes are
//                       left alone unless --raw: putting its serial port in raw mode is the
//                       writer's job (with OPOST/ONLCR left on, every 0x0A byte reaches us as
//                       0D 0A and the frames fail their CRC, which is reported, as it should be).
//   --file PATH         a file holding a captured byte stream; read to its end
//   --count N           stop once N ODOMETRY messages (CRC ok) were decoded, after --linger-ms
//                       more (default 150) so that messages sent right after the last ODOMETRY
//                       (e.g. its VISION_POSITION_DELTA) are kept too
//   --timeout-ms T      stop when T ms pass with no bytes received (default 5000)
//   --start-timeout-ms  the same limit before the first byte arrives (default: --timeout-ms)
//   --max-ms T          hard limit on the whole run (default 600000)
//   --out FILE          write the JSON lines there instead of stdout
//   --ready-file FILE   also write the READY line to FILE (written atomically) once listening
//
// When the input is open and listening, one line "READY udp 127.0.0.1:PORT" / "READY serial PATH"
// / "READY fd N" / "READY file PATH" goes to stderr. Send the data only after it.
//
// Output, one JSON object per line:
//   {"rx":i,"magic":253,"seq":..,"sysid":..,"compid":..,"msgid":..,"payloadLength":..,
//    "crcOk":true,"name":"ODOMETRY","fields":{"time_usec":"123",...},"trimOk":true,
//    "maxPayloadLength":233,"incompatFlags":0,"compatFlags":0,"signed":false}
//   Field names are MAVLink's own (time_usec, pose_covariance, ...). 64-bit integers are decimal
//   strings; non-finite floats are the strings "NaN", "Infinity", "-Infinity" (JSON has no NaN);
//   arrays are arrays. Fields of extensions that were not sent decode as 0 (MAVLink 2 rule).
//   A frame with a bad CRC: crcOk false, fields null, crcReceived/crcExpected given.
//   A frame whose msgid has no CRC_EXTRA known to node-mavlink: crcOk null, unknownMsgid true.
//   A frame that passed CRC but is in none of minimal/common/ardupilotmega: name null, fields null,
//   undecodable true.
//   trimOk: payload obeys MAVLink 2 zero-truncation (no trailing zero byte unless the payload is a
//   single byte) and is not longer than the message's full length (extensions included).
// Last line: {"summary":{packets,badCrc,unknownMsgid,undecodable,byMsgid,odometry,untrimmed,
//   skippedBytes,pendingBytes,datagrams,bytes,stopReason,splitter{valid,invalid,unknown}}}
//   packets = frames that passed the CRC check; byMsgid counts those by message id.
//   After a bad frame the splitter resynchronises one byte further, so bytes inside a corrupted
//   frame may show up as further bad frames or skipped bytes: any non-zero count means trouble.
//
// Exit status: 0 = stopped as asked (count reached, or input ended / went idle when no --count)
// and no bad frame, skipped or pending byte; 1 = some frame or byte was bad; 2 = --count not
// reached; 64 = usage error.

import { spawnSync } from 'node:child_process';
import dgram from 'node:dgram';
import fs from 'node:fs';
import tty from 'node:tty';
import {
  MavLinkPacketSplitter, MavLinkPacketParser, MavLinkProtocolV1, MavLinkProtocolV2,
  minimal, common, ardupilotmega, x25crc, MSG_ID_MAGIC_NUMBER,
} from 'node-mavlink';

const REGISTRY = { ...minimal.REGISTRY, ...common.REGISTRY, ...ardupilotmega.REGISTRY };
const ODOMETRY_ID = 331;

function usage(msg) {
  process.stderr.write(`decode.mjs: ${msg}\n` +
    'usage: node decode.mjs (--udp PORT | --serial PATH | --fd N | --file PATH) [--bind ADDR] [--count N]\n' +
    '       [--timeout-ms T] [--start-timeout-ms T] [--max-ms T] [--linger-ms T] [--raw | --no-raw]\n' +
    '       [--out FILE] [--ready-file FILE]\n');
  process.exit(64);
}

function parseArgs(argv) {
  const o = { bind: '127.0.0.1', count: null, timeoutMs: 5000, startTimeoutMs: null, maxMs: 600000, lingerMs: 150 };
  const intArg = (name, v, min) => {
    if (v === undefined || !/^\d+$/.test(v)) usage(`${name} needs a non-negative integer`);
    const n = Number(v);
    if (n < min) usage(`${name} must be >= ${min}`);
    return n;
  };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const next = () => { if (i + 1 >= argv.length) usage(`${a} needs a value`); return argv[++i]; };
    switch (a) {
      case '--udp': o.udp = intArg(a, next(), 0); if (o.udp > 65535) usage('--udp port out of range'); break;
      case '--serial': o.serial = next(); break;
      case '--file': o.file = next(); break;
      case '--fd': o.fd = intArg(a, next(), 0); break;
      case '--raw': o.raw = true; break;
      case '--no-raw': o.raw = false; break;
      case '--bind': o.bind = next(); break;
      case '--count': o.count = intArg(a, next(), 1); break;
      case '--timeout-ms': o.timeoutMs = intArg(a, next(), 1); break;
      case '--start-timeout-ms': o.startTimeoutMs = intArg(a, next(), 1); break;
      case '--max-ms': o.maxMs = intArg(a, next(), 1); break;
      case '--linger-ms': o.lingerMs = intArg(a, next(), 0); break;
      case '--out': o.out = next(); break;
      case '--ready-file': o.readyFile = next(); break;
      case '-h': case '--help': usage('help');
      default: usage(`unknown argument '${a}'`);
    }
  }
  const inputs = [o.udp, o.serial, o.fd, o.file].filter((x) => x !== undefined).length;
  if (inputs !== 1) usage('give exactly one of --udp, --serial, --fd, --file');
  if (o.raw === undefined) o.raw = o.serial !== undefined;
  if (o.startTimeoutMs === null) o.startTimeoutMs = o.timeoutMs;
  return o;
}

// JSON-safe value: bigint -> decimal string, non-finite number -> "NaN"/"Infinity"/"-Infinity".
function jsonValue(v) {
  if (typeof v === 'bigint') return v.toString();
  if (typeof v === 'number') return Number.isFinite(v) ? v : String(v);
  if (Array.isArray(v)) return v.map(jsonValue);
  return v;
}

function headerOf(buffer) {
  const magic = buffer[0];
  const Protocol = magic === MavLinkProtocolV2.START_BYTE ? MavLinkProtocolV2 : MavLinkProtocolV1;
  const h = new Protocol().header(buffer);
  return { magic, h, Protocol };
}

function frameBase(buffer) {
  const { magic, h } = headerOf(buffer);
  const base = {
    magic, seq: h.seq, sysid: h.sysid, compid: h.compid, msgid: h.msgid, payloadLength: h.payloadLength,
  };
  if (magic === MavLinkProtocolV2.START_BYTE) {
    base.incompatFlags = h.incompatibilityFlags;
    base.compatFlags = h.compatibilityFlags;
    base.signed = (h.incompatibilityFlags & MavLinkProtocolV2.IFLAG_SIGNED) !== 0;
  }
  return base;
}

// MAVLink 2 payload truncation rule (mavlink C: _mav_trim_payload): trailing zero bytes are cut,
// the first byte never is. MAVLink 1 frames always carry the full payload.
function trimCheck(buffer, payloadLength, clazz) {
  const magic = buffer[0];
  const off = magic === MavLinkProtocolV2.START_BYTE ? MavLinkProtocolV2.PAYLOAD_OFFSET : MavLinkProtocolV1.PAYLOAD_OFFSET;
  if (magic !== MavLinkProtocolV2.START_BYTE) return clazz ? payloadLength === clazz.PAYLOAD_LENGTH : true;
  if (payloadLength < 1) return false;
  if (clazz && payloadLength > clazz.PAYLOAD_LENGTH) return false;
  return payloadLength === 1 || buffer[off + payloadLength - 1] !== 0;
}

// The splitter, unchanged except that it tells us what it drops and what it keeps, in order.
class ReportingSplitter extends MavLinkPacketSplitter {
  constructor(onDropped) {
    super({}, { onCrcError: (buffer) => onDropped('badCrc', Buffer.from(buffer)) });
    this.onDropped = onDropped;
    this.skippedBytes = 0;
    this.order = [];  // FIFO of 'packet' markers and dropped-frame records, in stream order
  }
  findStartOfPacket(buffer, offset = 0) {
    const start = super.findStartOfPacket(buffer, offset);
    // _transform throws away the bytes before the start it is given: count them.
    if (start !== null && start > offset) this.skippedBytes += start - offset;
    return start;
  }
  validatePacket(buffer, Protocol) {
    const result = super.validatePacket(buffer, Protocol);
    if (result === 2 /* PacketValidationResult.UNKNOWN */) this.onDropped('unknownMsgid', Buffer.from(buffer));
    return result;
  }
  push(chunk) {
    if (chunk !== null) this.order.push({ kind: 'packet' });
    return super.push(chunk);
  }
  get pendingBytes() { return this.buffer.length; }
}

function main() {
  const opt = parseArgs(process.argv.slice(2));
  const outFd = opt.out ? fs.openSync(opt.out, 'w') : 1;
  const writeLine = (obj) => fs.writeSync(outFd, JSON.stringify(obj) + '\n');

  const stats = {
    packets: 0, badCrc: 0, unknownMsgid: 0, undecodable: 0, byMsgid: {}, odometry: 0, untrimmed: 0,
    skippedBytes: 0, pendingBytes: 0, datagrams: 0, bytes: 0, stopReason: null,
  };
  let rx = 0;

  const splitter = new ReportingSplitter((kind, buffer) => splitter.order.push({ kind, buffer }));
  const parser = new MavLinkPacketParser();
  splitter.pipe(parser);

  const emitDropped = ({ kind, buffer }) => {
    const line = { rx: rx++, ...frameBase(buffer) };
    const clazz = REGISTRY[line.msgid];
    if (kind === 'badCrc') {
      stats.badCrc++;
      const magicNumber = MSG_ID_MAGIC_NUMBER[line.msgid];
      const Protocol = headerOf(buffer).Protocol;
      const signedLen = line.signed ? 13 : 0;
      line.crcOk = false;
      line.crcReceived = new Protocol().crc(buffer);
      line.crcExpected = x25crc(buffer, 1, 2 + signedLen, magicNumber);
      line.name = clazz ? clazz.MSG_NAME : null;
    } else {
      stats.unknownMsgid++;
      line.crcOk = null;
      line.unknownMsgid = true;
      line.name = null;
    }
    line.fields = null;
    line.raw = buffer.toString('hex');
    writeLine(line);
  };

  // Everything the splitter dropped before this packet goes out first, then the packet.
  const drainDroppedUpToPacket = () => {
    while (splitter.order.length && splitter.order[0].kind !== 'packet') emitDropped(splitter.order.shift());
    if (splitter.order.length) splitter.order.shift();
  };

  let stopRequested = false;
  let lingerTimer = null;

  parser.on('data', (packet) => {
    drainDroppedUpToPacket();
    const line = { rx: rx++, ...frameBase(packet.buffer), crcOk: true };
    const clazz = REGISTRY[packet.header.msgid];
    stats.packets++;
    stats.byMsgid[line.msgid] = (stats.byMsgid[line.msgid] || 0) + 1;
    if (clazz) {
      const data = packet.protocol.data(packet.payload, clazz);
      line.name = clazz.MSG_NAME;
      line.fields = {};
      for (const f of clazz.FIELDS) line.fields[f.source] = jsonValue(data[f.name]);
      line.maxPayloadLength = clazz.PAYLOAD_LENGTH;
    } else {
      stats.undecodable++;
      line.name = null;
      line.fields = null;
      line.undecodable = true;
      line.raw = packet.buffer.toString('hex');
    }
    line.trimOk = trimCheck(packet.buffer, line.payloadLength, clazz);
    if (!line.trimOk) stats.untrimmed++;
    writeLine(line);
    if (line.msgid === ODOMETRY_ID && clazz) {
      stats.odometry++;
      if (opt.count !== null && stats.odometry >= opt.count && !lingerTimer) {
        lingerTimer = setTimeout(() => stop('count'), opt.lingerMs);
      }
    }
  });

  let finished = false;
  parser.on('end', () => {
    while (splitter.order.length) {
      const e = splitter.order.shift();
      if (e.kind !== 'packet') emitDropped(e);
    }
    stats.skippedBytes = splitter.skippedBytes;
    stats.pendingBytes = splitter.pendingBytes;
    stats.splitter = {
      valid: splitter.validPackages, invalid: splitter.invalidPackages, unknown: splitter.unknownPackagesCount,
    };
    writeLine({ summary: stats });
    if (outFd !== 1) fs.closeSync(outFd);
    finished = true;
    const bad = stats.badCrc + stats.unknownMsgid + stats.undecodable + stats.untrimmed + stats.skippedBytes + stats.pendingBytes;
    let code = bad > 0 ? 1 : 0;
    if (opt.count !== null && stats.odometry < opt.count) code = 2;
    process.exit(code);
  });

  // ---- timers ----
  let idleTimer = null;
  const armIdle = (ms) => {
    if (idleTimer) clearTimeout(idleTimer);
    idleTimer = setTimeout(() => stop('idle-timeout'), ms);
  };
  const maxTimer = setTimeout(() => stop('max-time'), opt.maxMs);
  let closeInput = () => {};

  function stop(reason) {
    if (stopRequested) return;
    stopRequested = true;
    stats.stopReason = reason;
    if (idleTimer) clearTimeout(idleTimer);
    if (lingerTimer) clearTimeout(lingerTimer);
    clearTimeout(maxTimer);
    try { closeInput(); } catch { /* already closed */ }
    splitter.end();
    // A broken stream must not hang the process forever.
    setTimeout(() => { if (!finished) { process.stderr.write('decode.mjs: pipeline did not finish\n'); process.exit(1); } }, 5000).unref();
  }

  const feed = (chunk) => {
    if (stopRequested) return;
    stats.bytes += chunk.length;
    armIdle(opt.timeoutMs);
    splitter.write(chunk);
  };

  const announce = (what) => {
    const line = `READY ${what}`;
    if (opt.readyFile) {
      const tmp = `${opt.readyFile}.tmp${process.pid}`;
      fs.writeFileSync(tmp, line + '\n');
      fs.renameSync(tmp, opt.readyFile);
    }
    process.stderr.write(line + '\n');
    armIdle(opt.startTimeoutMs);
  };

  if (opt.udp !== undefined) {
    // a large receive buffer, so that a replay that sends faster than real time is not cut short
    // by the kernel (losses would show up as seq gaps); Linux caps it at net.core.rmem_max
    const sock = dgram.createSocket({ type: 'udp4', recvBufferSize: 8 << 20 });
    sock.on('error', (e) => { process.stderr.write(`decode.mjs: udp: ${e.message}\n`); stop('error'); });
    sock.on('message', (msg) => { stats.datagrams++; feed(msg); });
    closeInput = () => sock.close();
    sock.bind(opt.udp, opt.bind, () => {
      const a = sock.address();
      try { stats.udpRecvBufferBytes = sock.getRecvBufferSize(); } catch { /* not essential */ }
      announce(`udp ${a.address}:${a.port}`);
    });
  } else if (opt.serial !== undefined || opt.fd !== undefined) {
    let fd = opt.fd;
    if (opt.serial !== undefined) {
      try {
        fd = fs.openSync(opt.serial, fs.constants.O_RDWR | fs.constants.O_NOCTTY);
      } catch (e) {
        process.stderr.write(`decode.mjs: cannot open ${opt.serial}: ${e.message}\n`);
        process.exit(64);
      }
    }
    let stream;
    if (tty.isatty(fd)) {
      stream = new tty.ReadStream(fd);
      if (opt.raw) {
        // stty's "raw" is cfmakeraw (input and output processing off); libuv's raw mode leaves
        // OPOST/ONLCR on, so it is only the fallback.
        const r = spawnSync('stty', ['raw', '-echo'], { stdio: [fd, 'ignore', 'pipe'] });
        if (r.status !== 0) stream.setRawMode(true);
      }
    } else {
      stream = fs.createReadStream(null, { fd });
    }
    stream.on('data', feed);
    // A pty reports EIO once the other side is closed: that is the end of the input.
    stream.on('error', (e) => { if (e.code !== 'EIO') process.stderr.write(`decode.mjs: serial: ${e.message}\n`); stop(e.code === 'EIO' ? 'eof' : 'error'); });
    stream.on('end', () => stop('eof'));
    closeInput = () => { stream.pause(); stream.destroy(); };
    announce(opt.serial !== undefined ? `serial ${opt.serial}` : `fd ${fd}`);
  } else {
    const stream = fs.createReadStream(opt.file);
    stream.on('open', () => announce(`file ${opt.file}`));
    stream.on('data', feed);
    stream.on('error', (e) => { process.stderr.write(`decode.mjs: ${e.message}\n`); stop('error'); });
    stream.on('end', () => stop('eof'));
    closeInput = () => stream.destroy();
  }
}

main();
