"""Checks an emm timeline (Chrome/Perfetto trace-event JSON) with Python's
own json module, a reader independent of emm's.

usage: timeline.py FILE [--report REPORT.json] [--channels N] [--phases N]
                        [--capped N]
  --report    every DMA transfer of the report's first result (dma.transfers)
              is one complete event on a DMA channel's track
  --channels  the number of DMA channel tracks
  --phases    at least N phase events
  --capped    the cap was hit: exactly N events (metadata events aside) and
              otherData says so
"""
import json
import sys


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def main():
    args = sys.argv[1:]
    path = args.pop(0)
    opts = dict(zip(args[::2], args[1::2]))
    with open(path) as f:
        doc = json.load(f)
    events = doc["traceEvents"]
    meta = doc["otherData"]
    names = {e["tid"]: e["args"]["name"] for e in events
             if e["ph"] == "M" and e["name"] == "thread_name"}
    channels = {tid for tid, name in names.items() if name.startswith("DMA channel ")}
    counted = [e for e in events if e["ph"] != "M"]
    if meta["events"] != len(counted):
        fail("otherData says %d events, the file holds %d" % (meta["events"], len(counted)))
    transfers = [e for e in counted if e["ph"] == "X" and e["tid"] in channels]
    for e in transfers:
        if e["dur"] < 0 or e["ts"] < 0 or "bytes" not in e["args"]:
            fail("a bad transfer event: %r" % e)
    print("%s: %d events, %d tracks, %d DMA channels, %d transfers, capped %s"
          % (path, len(counted), len(names), len(channels), len(transfers), meta["capped"]))
    if "--channels" in opts and len(channels) != int(opts["--channels"]):
        fail("%d DMA channel tracks, expected %s" % (len(channels), opts["--channels"]))
    if "--report" in opts:
        with open(opts["--report"]) as f:
            report = json.load(f)
        want = report["results"][0]["dma"]["transfers"]
        if meta["capped"]:
            fail("the cap was hit")
        if len(transfers) != want or meta["transfers"] != want:
            fail("%d transfer events, the report has %d transfers" % (len(transfers), want))
    if "--phases" in opts:
        phases = [e for e in counted if e.get("cat") == "phase"]
        if len(phases) < int(opts["--phases"]):
            fail("%d phases, expected at least %s" % (len(phases), opts["--phases"]))
    if "--capped" in opts:
        cap = int(opts["--capped"])
        if not meta["capped"] or meta["event_cap"] != cap or len(counted) != cap:
            fail("capped %s, cap %s, %d events: expected the cap of %d hit"
                 % (meta["capped"], meta["event_cap"], len(counted), cap))
        if meta["dropped_events"] <= 0 or not transfers:
            fail("nothing dropped, or no transfer kept")


main()
