"""The agent's side of the live loop (`kinect-agent serve`): the server's commands in, one set recorded with live
feedback out, the set kept on disk while it is recorded and queued for upload when it ends."""
