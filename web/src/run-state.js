import { check } from './messages.js';

// What the page knows of one run, built from the server's messages in order (a live stream or a
// report's embedded list alike, so that a live run and its report look the same). Views subscribe
// with on(type, fn) and are told what changed.
export class RunState {
  constructor() {
    this.listeners = new Map();
    this.reset();
  }

  reset() {
    this.task = null;
    this.stats = null;
    this.events = [];
    this.eventIndices = new Set();
    this.views = new Map();  // port -> the newest view message
    this.poses = new Map();  // port -> every pose view seen, in order: the views visited
    this.end = null;
    this.problems = [];
    this.messageCount = 0;
  }

  on(type, fn) {
    if (!this.listeners.has(type)) this.listeners.set(type, []);
    this.listeners.get(type).push(fn);
  }

  emit(type, arg) {
    for (const fn of this.listeners.get(type) ?? []) {
      try {
        fn(arg, this);
      } catch (e) {
        // One panel failing must not stop the others: its error is shown like a bad message.
        console.error(e);
        this.addProblem(`the ${type} panel failed: ${e.message}`);
      }
    }
  }

  addProblem(text) {
    this.problems.push(text);
    if (this.problems.length > 200) this.problems.splice(0, this.problems.length - 200);
    this.emit('problem', text);
  }

  apply(msg) {
    this.messageCount++;
    const problems = check(msg);
    if (problems.length) {
      for (const p of problems) this.addProblem(`message ${this.messageCount}: ${p}`);
      return;
    }
    if (msg.type !== 'task' && !this.task) {
      this.addProblem(`message ${this.messageCount}: a "${msg.type}" message came before the task message`);
      return;
    }
    switch (msg.type) {
      case 'task':
        // Every connection starts with the task: a reconnection starts the picture again.
        if (this.task) this.reset();
        this.task = msg;
        this.emit('task', msg);
        break;
      case 'stats':
        this.stats = msg;
        this.emit('stats', msg);
        break;
      case 'event':
        if (this.eventIndices.has(msg.index)) return;
        this.eventIndices.add(msg.index);
        this.events.push(msg);
        this.emit('event', msg);
        break;
      case 'view': {
        const previous = this.views.get(msg.port);
        if (previous && previous.seq === msg.seq && msg.seq !== undefined) return;
        this.views.set(msg.port, msg);
        if (msg.view.kind === 'pose') {
          if (!this.poses.has(msg.port)) this.poses.set(msg.port, []);
          const list = this.poses.get(msg.port);
          if (!list.some((p) => p.seq === msg.seq && msg.seq !== undefined)) list.push(msg);
        }
        this.emit('view', msg);
        break;
      }
      case 'end':
        this.end = msg;
        this.emit('end', msg);
        break;
    }
  }

  // The time of the newest thing known, seconds since the run's start.
  get now() {
    let t = this.stats?.t ?? 0;
    const last = this.events[this.events.length - 1];
    if (last && last.t > t) t = last.t;
    return t;
  }
}
