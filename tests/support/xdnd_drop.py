"""Drops a file on an X11 window as a file manager does, by the XDND protocol (version 5).

    python3 xdnd_drop.py WINDOW_ID PATH

xdotool can press keys and buttons but cannot drag data between clients, so tests/view.rs uses
this to check that `caustica view` opens a dropped file. The script plays the drag source: it
owns the XdndSelection, sends XdndEnter (offering text/uri-list) and XdndPosition to the target,
answers the target's request for the selection with PATH's file:// URI, and once the target has
accepted, sends XdndDrop and waits for XdndFinished.

Exit status 0: the target accepted the drop and said it finished; 1: it refused or did not answer
(the reason is on standard error). Needs python3-xlib.
"""

import sys
import time
import urllib.parse
from pathlib import Path

from Xlib import X, Xatom, display
from Xlib.protocol import event

XDND_VERSION = 5
# A target answers within milliseconds; a viewer compiling its kernel may take seconds to read events.
PATIENCE_S = 30.0


def fail(why):
    print(f"xdnd_drop: {why}", file=sys.stderr)
    sys.exit(1)


def main():
    if len(sys.argv) != 3:
        fail("usage: xdnd_drop.py WINDOW_ID PATH")
    target_id = int(sys.argv[1], 0)
    uri = "file://" + urllib.parse.quote(str(Path(sys.argv[2]).resolve())) + "\r\n"

    d = display.Display()
    atom = lambda name: d.intern_atom(name)
    target = d.create_resource_object("window", target_id)
    aware = target.get_full_property(atom("XdndAware"), Xatom.ATOM)
    if aware is None or not aware.value:
        fail(f"window {target_id:#x} is not XdndAware")
    version = min(XDND_VERSION, aware.value[0])

    # The drag source: an unmapped window of ours that owns the selection and receives the replies.
    source = d.screen().root.create_window(0, 0, 1, 1, 0, X.CopyFromParent)
    uri_list = atom("text/uri-list")
    source.set_selection_owner(atom("XdndSelection"), X.CurrentTime)

    def send(name, data):
        message = event.ClientMessage(window=target, client_type=atom(name), data=(32, data))
        target.send_event(message, event_mask=X.NoEventMask)
        d.flush()

    # Where a pointer over the target's middle is, in root coordinates.
    geometry = target.get_geometry()
    origin = target.translate_coords(d.screen().root, 0, 0)
    x, y = -origin.x + geometry.width // 2, -origin.y + geometry.height // 2

    send("XdndEnter", [source.id, version << 24, uri_list, 0, 0])
    send("XdndPosition", [source.id, 0, (x << 16) | y, X.CurrentTime, atom("XdndActionCopy")])

    accepted = answered = dropped = False
    deadline = time.monotonic() + PATIENCE_S
    while time.monotonic() < deadline:
        if not d.pending_events():
            time.sleep(0.01)
            continue
        e = d.next_event()
        if e.type == X.SelectionRequest and e.selection == atom("XdndSelection"):
            # The target reads the data now (winit does so on XdndPosition, before the drop).
            ok = e.target == uri_list
            if ok:
                e.requestor.change_property(e.property, uri_list, 8, uri.encode())
            reply = event.SelectionNotify(time=e.time, requestor=e.requestor, selection=e.selection, target=e.target, property=e.property if ok else X.NONE)
            e.requestor.send_event(reply)
            d.flush()
            answered = answered or ok
        elif e.type == X.ClientMessage and e.client_type == atom("XdndStatus"):
            if not e.data[1][1] & 1:
                fail("the target refused the drop (XdndStatus without the accept bit)")
            accepted = True
        elif e.type == X.ClientMessage and e.client_type == atom("XdndFinished"):
            if version >= 5 and not e.data[1][1] & 1:
                fail("the target finished without accepting the drop")
            return
        # Drop once the target has both accepted and read the URI: the SelectionNotify sent above
        # then reaches it before the XdndDrop.
        if accepted and answered and not dropped:
            send("XdndDrop", [source.id, 0, X.CurrentTime, 0, 0])
            dropped = True
    fail(f"no answer from window {target_id:#x} within {PATIENCE_S} s (accepted: {accepted}, data read: {answered}, dropped: {dropped})")


main()
