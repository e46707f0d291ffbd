// The live stream from fba-run: a WebSocket on the page's own address with the page's token, the
// first one opened by index.html before this script loaded (window.fbaEarlyStream, with what it
// has said since). When it closes before the run's end message, it tries again with a growing
// pause; the server sends the task message first on every connection, which starts the picture
// again.

export function connectLive({ token, onMessage, onStatus }) {
  let socket = null;
  let retry = 0;
  let ended = false;
  let timer = 0;

  function open() {
    const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
    const url = `${scheme}//${location.host}/ws?token=${encodeURIComponent(token)}`;
    onStatus('connecting', `connecting to ${location.host}…`);
    const early = window.fbaEarlyStream;
    window.fbaEarlyStream = null;
    try {
      socket = early?.socket ?? new WebSocket(url);
    } catch (e) {
      onStatus('error', `cannot open the live stream: ${e.message}`);
      return;
    }
    const handlers = { open: onOpen, message: onMessageEvent, close: onClose };
    for (const [type, handler] of Object.entries(handlers)) socket.addEventListener(type, handler);
    if (early) {
      const said = early.events;
      early.events = null;
      for (const ev of said) handlers[ev.type](ev);
    }
  }

  // Marked at the event's own time: one the early stream kept is handled later than it came.
  function onOpen(ev) {
    performance.mark('fba-live-open', { startTime: ev.timeStamp });
    retry = 0;
    onStatus('live', 'live');
    socket.send(JSON.stringify({ type: 'ping' }));
  }

  function onMessageEvent(ev) {
    let msg;
    try {
      msg = JSON.parse(ev.data);
    } catch (e) {
      onStatus('problem', `a message from the server is not JSON: ${e.message}`);
      return;
    }
    if (msg.type === 'task') performance.mark('fba-task-received', { startTime: ev.timeStamp });
    if (msg.type === 'end') ended = true;
    onMessage(msg);
  }

  function onClose(ev) {
    if (ended) {
      onStatus('ended', 'the run has ended; the server closed the stream');
      return;
    }
    retry++;
    const wait = Math.min(10, 0.5 * 2 ** Math.min(retry, 5));
    const why = ev.code === 1006 ? 'the server is unreachable (has fba-run stopped?)' : `closed (${ev.code}${ev.reason ? ': ' + ev.reason : ''})`;
    onStatus('retrying', `${why}; trying again in ${wait} s`);
    timer = setTimeout(open, wait * 1000);
  }

  open();
  return {
    close() {
      ended = true;
      clearTimeout(timer);
      socket?.close();
    },
  };
}
