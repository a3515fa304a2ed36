"""One request to a weaver serve on 127.0.0.1, on a connection of its own,
for the serve checks (check_serve.py, check_serve_hostile.py)."""
import http.client


def exchange(port, method, path, body=None, headers=None, timeout=60):
    """The status, the response's headers (a dict) and its body."""
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    c.request(method, path, body=body, headers=headers or {})
    r = c.getresponse()
    data = r.read()
    c.close()
    return r.status, dict(r.getheaders()), data


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
