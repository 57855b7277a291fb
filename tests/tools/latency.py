# Input-to-response of the live editor under Xvfb: clicks on the View menu and in the viewport,
# timed from the xdotool call to the first frame the editor reports after handling it.
# Usage: python3 tests/tools/latency.py BINARY SCENE LABEL (an Xvfb on :77, xdotool; see BENCHMARKS.md).
import subprocess, sys, time, os
binary, scene, out = sys.argv[1], sys.argv[2], sys.argv[3]
env = dict(os.environ, DISPLAY=':77', VOXBRICK_REPORT='/tmp/lat-report.log')
try: os.remove('/tmp/lat-report.log')
except FileNotFoundError: pass
cfg = '/tmp/lat-config'; subprocess.run(['rm','-rf',cfg]); os.makedirs(cfg)
env['VOXBRICK_CONFIG_DIR'] = cfg
p = subprocess.Popen([binary, scene, '--window', '960x540'], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
def lines():
    try: return open('/tmp/lat-report.log').read().splitlines()
    except FileNotFoundError: return []
t0=time.time()
while not any(l.startswith('loaded ') for l in lines()):
    time.sleep(0.05)
    if time.time()-t0>120: sys.exit('no load')
time.sleep(8)  # past the first frames
w = subprocess.run(['xdotool','search','--name','voxbrick'],env=env,capture_output=True,text=True).stdout.split()[0]
subprocess.run(['xdotool','windowfocus',w],env=env)
res=[]
for k in range(12):
    n=len(lines())
    x = 90 if k%2==0 else 480
    subprocess.run(['xdotool','mousemove',str(x),'11' if k%2==0 else '300'],env=env)
    time.sleep(0.3)
    n=len(lines())
    t=time.time()
    subprocess.run(['xdotool','click','1'],env=env)
    seen=False
    while True:
        ls=lines()[n:]
        idx=[i for i,l in enumerate(ls) if l.startswith('input press')]
        if idx and any(l.startswith('frame ') for l in ls[idx[0]:]):
            res.append((k%2, time.time()-t)); break
        if time.time()-t>30: res.append((k%2, float('inf'))); break
        time.sleep(0.005)
    time.sleep(1.0)
fr=[l for l in lines() if l.startswith('frame ')]
p.kill()
def summary(times):
    times = sorted(times)
    return 'median %.3f s, max %.3f s, of %d clicks' % (times[len(times)//2], times[-1], len(times))
print(out, 'all:', summary([t for _, t in res]), '· View menu:', summary([t for k, t in res if k == 0]),
      '· viewport:', summary([t for k, t in res if k == 1]), '· frames %d' % len(fr))
