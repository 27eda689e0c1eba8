// The page's WebSocket to the gateway, reopened with backoff whenever it
// closes (gateway restarted, network gone). JSON messages go to onMessage,
// frames (binary) to onFrame, already unpacked.
import { Backoff } from './backoff.js';
import { unpackFrame } from './frame_packet.js';

export class GatewaySocket {
  constructor({ url, onOpen, onClose, onMessage, onFrame }) {
    Object.assign(this, { url, onOpen, onClose, onMessage, onFrame });
    this.backoff = new Backoff({ firstMs: 500, maxMs: 8000 });
    this.ws = null;
    this.connect();
  }

  connect() {
    const ws = new WebSocket(this.url);
    ws.binaryType = 'arraybuffer';
    this.ws = ws;
    ws.onopen = () => {
      this.backoff.reset();
      this.onOpen();
    };
    ws.onmessage = (e) => {
      if (typeof e.data === 'string') this.onMessage(JSON.parse(e.data));
      else this.onFrame(unpackFrame(e.data));
    };
    ws.onclose = () => {
      const delayMs = this.backoff.next();
      this.onClose(delayMs);
      setTimeout(() => this.connect(), delayMs);
    };
  }

  // False when the socket is not open (the message is dropped).
  send(message) {
    if (this.ws?.readyState !== WebSocket.OPEN) return false;
    this.ws.send(JSON.stringify(message));
    return true;
  }
}
