# Click-to-visible UI response of the live editor under Xvfb, measured on the screen: the View
# menu is opened and closed by clicks on its button while the path tracer refines, and each
# response is the time from the button's release (sent with XTest, egui clicks on release)
# to the first moment the menu's area of the X server's framebuffer changed (read with
# XGetImage every 2 ms), whatever the editor reports. (`xdotool click` itself takes ~100 ms:
# it sleeps after the release, so it cannot time anything shorter.)
# Usage: /usr/bin/python3 tests/tools/latency.py BINARY SCENE|- LABEL [WxH] [CLICKS]
# (an Xvfb on :77 at least WxH, xdotool, python3-xlib; see BENCHMARKS.md). SCENE "-" is the
# built-in default scene.
import os, subprocess, sys, time
from Xlib import X, display
from Xlib.ext import xtest

binary, scene, label = sys.argv[1], sys.argv[2], sys.argv[3]
size = sys.argv[4] if len(sys.argv) > 4 else '1280x720'
clicks = int(sys.argv[5]) if len(sys.argv) > 5 else 16
env = dict(os.environ, DISPLAY=':77', VOXBRICK_REPORT='/tmp/lat-report.log')
try:
    os.remove('/tmp/lat-report.log')
except FileNotFoundError:
    pass
cfg = '/tmp/lat-config'
subprocess.run(['rm', '-rf', cfg])
os.makedirs(cfg)
env['VOXBRICK_CONFIG_DIR'] = cfg
args = [binary] + ([] if scene == '-' else [scene]) + ['--window', size]
p = subprocess.Popen(args, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def lines():
    try:
        return open('/tmp/lat-report.log').read().splitlines()
    except FileNotFoundError:
        return []


def widget(name):
    for l in reversed(lines()):
        if l.startswith('widget ') and l.endswith(' ' + name):
            x, y = l.split()[1:3]
            return int(float(x)), int(float(y))
    return None


t0 = time.time()
while not any(l.startswith('frame ') for l in lines()) or widget('View') is None:
    time.sleep(0.05)
    if time.time() - t0 > 180 or p.poll() is not None:
        sys.exit('the editor showed no frame')
time.sleep(8)  # past the first frames: the tracer is refining
d = display.Display(':77')
root = d.screen().root
w = subprocess.run(['xdotool', 'search', '--name', 'voxbrick'], env=env,
                   capture_output=True, text=True).stdout.split()[0]
subprocess.run(['xdotool', 'windowfocus', w], env=env)
vx, vy = widget('View')
# The area the View menu opens over (below and right of its button).
area = (max(vx - 20, 0), vy + 12, 160, 120)


def grab():
    return root.get_image(area[0], area[1], area[2], area[3], X.ZPixmap, 0xffffffff).data


subprocess.run(['xdotool', 'mousemove', str(vx), str(vy)], env=env)
time.sleep(0.5)
res = []
for k in range(clicks):
    before = grab()
    xtest.fake_input(d, X.ButtonPress, 1)
    d.sync()
    time.sleep(0.03)
    xtest.fake_input(d, X.ButtonRelease, 1)
    d.sync()
    t = time.time()
    while True:
        if grab() != before:
            res.append((k % 2, time.time() - t))
            break
        if time.time() - t > 30:
            res.append((k % 2, float('inf')))
            break
        time.sleep(0.002)
    time.sleep(1.0)
traced = [l for l in lines() if l.startswith('frame ')]
p.kill()


def summary(times):
    times = sorted(times)
    return 'median %.0f ms, max %.0f ms, of %d' % (times[len(times) // 2] * 1e3, times[-1] * 1e3, len(times))


print(label, size, '· all:', summary([t for _, t in res]), '· menu opens:',
      summary([t for k, t in res if k == 0]), '· menu closes:', summary([t for k, t in res if k == 1]),
      '· frames shown %d, last spp %s' % (len(traced), traced[-1].split()[-1] if traced else '-'))
print('  each (ms, in order):', ' '.join('%.0f' % (t * 1e3) for _, t in res))
