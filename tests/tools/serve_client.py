"""One request to a weaver serve on 127.0.0.1, on a connection of its own,
for the serve checks (check_serve.py, check_serve_hostile.py)."""
import http.client
import socket


def exchange(port, method, path, body=None, headers=None, timeout=60):
    """The status, the response's headers (a dict) and its body."""
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    c.request(method, path, body=body, headers=headers or {})
    r = c.getresponse()
    data = r.read()
    c.close()
    return r.status, dict(r.getheaders()), data


def read_to_end(so):
    """Everything the server sends on socket so until it closes."""
    got = bytearray()  # not bytes: bytes += bytes copies it all each time (minutes for 100 MB)
    while chunk := so.recv(65536):
        got += chunk
    return bytes(got)


def raw(port, data, timeout=20):
    """Sends the bytes data as they are on a connection of its own: the
    server's answer up to its close."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as so:
        so.sendall(data)
        return read_to_end(so)


def start_server(weaver, db, log_path, *options):
    """weaver serve DB on a port of the system's choosing: the process and
    its port, read from the URL on its first line (its stderr to log_path)."""
    import subprocess
    log = open(log_path, "w")
    server = subprocess.Popen([weaver, "serve", db, "--port", "0", *options],
                              stdout=subprocess.PIPE, stderr=log, text=True)
    first = server.stdout.readline()
    if "http://127.0.0.1:" not in first:
        server.kill()
        raise RuntimeError(f"no URL on the first line: {first!r} {open(log_path).read()}")
    return server, int(first.split("http://127.0.0.1:")[1].split("/")[0])


def stop_server(server, timeout=10):
    """SIGTERM to a weaver serve process: its exit status, or None (and the
    process killed) when it does not stop within timeout seconds."""
    import signal
    import subprocess
    server.send_signal(signal.SIGTERM)
    try:
        return server.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        server.kill()
        return None
