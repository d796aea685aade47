"""A Python agent that uses ``beacon::Beacon`` without a class written for it: it learns the type
from the descriptor that ``caravan-beacon`` registered with the group.

Run with the node's environment (``CARAVAN_GROUP``, ``CARAVAN_NODE``) while the beacon runs.
Prints the first broadcast it receives as JSON (``to_dict()``) on one line; then publishes, on
``beacon/set`` with the same class, the label and position given as JSON in the first argument
until a broadcast says them, and prints that broadcast. Exits 1 if none does within 10 s.
"""

import json
import sys

from caravan import CaravanError, Node, main, schemas

STEPS = 200  # at 20 Hz: 10 s for the beacon (10 Hz) to take the new label


def agent():
    told = json.loads(sys.argv[1])
    node = Node.from_env()
    Beacon = node.message_type("beacon::Beacon")
    broadcasts = node.subscriber(Beacon, "beacon")
    setter = node.publisher(Beacon, "beacon/set")
    wanted = Beacon()
    schemas.set_fixed_str(wanted, "label", told["label"])
    for axis, value in told["position"].items():
        setattr(wanted.position, axis, value)
    seen = []

    def step(s):
        for msg in broadcasts.receive_all():
            view = msg.payload.to_dict()
            if not seen:
                print(json.dumps(view), flush=True)
            seen.append(view)
            if view["label"] == told["label"]:
                print(json.dumps(view), flush=True)
                s.stop()
                return
        if seen:
            setter.publish(wanted)
        if s.index >= STEPS:
            raise CaravanError(f"the beacon did not take the label in {STEPS} steps: {seen[-1:]}")

    node.run(step, rate="20Hz")


if __name__ == "__main__":
    main(agent)
