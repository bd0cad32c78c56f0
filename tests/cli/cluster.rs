//! docs/scale-out.md's Slurm recipe on a real Slurm: a single-node cluster (slurmctld, slurmd and
//! munged, as Debian's `slurm-wlm` and `munge` install them) started in a temporary directory runs the
//! doc's `render-part.sbatch` and its commands as printed. The merge job's image is the single render's,
//! byte for byte; a task cancelled mid-render leaves the merge job pending, `whitted merge` names the
//! part, and the doc's rerun of that task merges into the same bytes.

use std::collections::HashMap;
use std::fs::File;
use std::io::Read;
use std::os::unix::fs::PermissionsExt;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use crate::common::{self, ok as run, root};
use crate::scale_out::recipe;

/// How long a daemon, a job or a state may take on a loaded 2-core machine before the test gives up.
const PATIENCE: Duration = Duration::from_secs(300);

/// One line of `scontrol -o show job`: its `KEY=VALUE` fields.
type Job = HashMap<String, String>;

/// A Slurm cluster of one node in a temporary directory, stopped when dropped (also when an assertion
/// fails): its daemons by pid, then whatever they left running (job steps, the jobs' processes).
struct Slurm {
    dir: tempfile::TempDir,
    conf: PathBuf,
    /// The PATH of every command: the built `whitted` first, then the daemons' `sbin` directories, which
    /// a user's PATH may lack.
    path: String,
    daemons: Vec<(&'static str, Child)>,
}

fn output(cmd: &mut Command) -> Output {
    cmd.output()
        .unwrap_or_else(|e| panic!("{cmd:?} does not run: {e}"))
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A port no one listens on now.
fn free_ports() -> (u16, u16) {
    let a = std::net::TcpListener::bind(("0.0.0.0", 0)).unwrap();
    let b = std::net::TcpListener::bind(("0.0.0.0", 0)).unwrap();
    (a.local_addr().unwrap().port(), b.local_addr().unwrap().port())
}

impl Slurm {
    fn start() -> Slurm {
        let dir = tempfile::Builder::new()
            .prefix("whitted-slurm")
            .tempdir()
            .unwrap();
        let d = dir.path().to_path_buf();
        let bin = PathBuf::from(env!("CARGO_BIN_EXE_whitted"));
        let path = format!(
            "{}:{}:/usr/sbin:/sbin",
            bin.parent().unwrap().display(),
            std::env::var("PATH").unwrap_or_default()
        );
        let mut slurm = Slurm {
            dir,
            conf: d.join("slurm.conf"),
            path,
            daemons: Vec::new(),
        };

        for dir in ["state", "spool"] {
            std::fs::create_dir(d.join(dir)).unwrap();
        }
        // munged refuses a socket whose directories others cannot enter, and a key others can read.
        let munge = d.join("munge");
        std::fs::create_dir(&munge).unwrap();
        for dir in [&d, &munge] {
            std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o755)).unwrap();
        }
        let key = munge.join("munge.key");
        let mut bytes = vec![0; 1024];
        File::open("/dev/urandom")
            .unwrap()
            .read_exact(&mut bytes)
            .unwrap();
        std::fs::write(&key, bytes).unwrap();
        std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o400)).unwrap();
        let socket = munge.join("munge.socket");
        let mut munged = slurm.command("munged");
        munged.arg("--foreground").args(
            [
                ("--socket", &socket),
                ("--key-file", &key),
                ("--pid-file", &munge.join("munged.pid")),
                ("--seed-file", &munge.join("munged.seed")),
            ]
            .map(|(option, file)| format!("{option}={}", file.display())),
        );
        // As root, munged runs as its own user, as Debian's service runs it; otherwise everything runs as
        // the test's user, Slurm's daemons included.
        let euid = unsafe { libc::geteuid() };
        if euid == 0 {
            let pw = unsafe { libc::getpwnam(c"munge".as_ptr()) };
            assert!(!pw.is_null(), "no munge user: apt-get install munge");
            let (uid, gid) = unsafe { ((*pw).pw_uid, (*pw).pw_gid) };
            for file in [&munge, &key] {
                std::os::unix::fs::chown(file, Some(uid), Some(gid)).unwrap();
            }
            munged.uid(uid).gid(gid);
        }
        slurm.spawn("munged", munged);
        slurm.wait_for("munged's socket", || socket.exists());

        let user = text(&output(Command::new("id").arg("-un")).stdout);
        let host = text(&output(Command::new("hostname").arg("-s")).stdout);
        let (user, host) = (user.trim(), host.trim());
        let cpus = std::thread::available_parallelism().unwrap().get();
        let (ctld_port, slurmd_port) = free_ports();
        let at = |name: &str| d.join(name).display().to_string();
        // Accounting, cgroups and MPI stay off: nothing of the machine's is touched. The script asks 16
        // CPUs a task, so the node claims at least 16 (config_overrides: slurmd believes this file
        // rather than the hardware), and the node is reached at 127.0.0.1 whatever the host name resolves to.
        // The main scheduling loop runs every second instead of every minute: a job whose dependency was
        // met starts then, not up to a minute later (a big cluster's default, not a behaviour tested).
        let conf = format!(
            "ClusterName=whitted
SlurmctldHost={host}(127.0.0.1)
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
SlurmUser={user}
SlurmdUser={user}
AuthType=auth/munge
AuthInfo=socket={socket}
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
SchedulerParameters=sched_interval=1
SlurmdParameters=config_overrides
StateSaveLocation={state}
SlurmdSpoolDir={spool}
SlurmctldPidFile={ctld_pid}
SlurmdPidFile={slurmd_pid}
NodeName={host} NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN
PartitionName=whitted Nodes={host} Default=YES MaxTime=INFINITE State=UP
",
            socket = socket.display(),
            state = at("state"),
            spool = at("spool"),
            ctld_pid = at("slurmctld.pid"),
            slurmd_pid = at("slurmd.pid"),
            cpus = cpus.max(16),
        );
        std::fs::write(&slurm.conf, conf).unwrap();
        for daemon in ["slurmctld", "slurmd"] {
            let mut cmd = slurm.command(daemon);
            cmd.arg("-D");
            slurm.spawn(daemon, cmd);
        }
        slurm.wait_for("the node to be idle", || {
            let out = slurm.command("sinfo").args(["-h", "-N", "-o", "%T"]).output();
            out.is_ok_and(|o| text(&o.stdout).trim() == "idle")
        });
        slurm
    }

    /// `program` with this cluster's configuration and PATH, and none of the Slurm variables of a job
    /// this test may itself be running in.
    fn command(&self, program: &str) -> Command {
        let mut cmd = Command::new(program);
        for (name, _) in std::env::vars_os() {
            let name = name.to_string_lossy();
            if name.starts_with("SLURM_") || name.starts_with("SBATCH_") || name.starts_with("SQUEUE_") {
                cmd.env_remove(&*name);
            }
        }
        cmd.env("SLURM_CONF", &self.conf).env("PATH", &self.path);
        cmd
    }

    /// Starts a daemon in the foreground, its output in `NAME.log`.
    fn spawn(&mut self, name: &'static str, mut cmd: Command) {
        let log = File::create(self.dir.path().join(format!("{name}.log"))).unwrap();
        cmd.stdin(Stdio::null())
            .stdout(log.try_clone().unwrap())
            .stderr(log);
        let child = cmd
            .spawn()
            .unwrap_or_else(|e| panic!("{name} does not start: {e}"));
        self.daemons.push((name, child));
    }

    /// The end of each daemon's log, for a failure's message.
    fn logs(&self) -> String {
        let mut out = String::new();
        for (name, _) in &self.daemons {
            let log =
                std::fs::read_to_string(self.dir.path().join(format!("{name}.log"))).unwrap_or_default();
            let lines: Vec<&str> = log.lines().collect();
            let tail = lines[lines.len().saturating_sub(30)..].join("\n");
            out += &format!("\n--- {name}.log (end) ---\n{tail}");
        }
        out
    }

    /// Polls `done` until it holds; fails after PATIENCE, or at once if a daemon has exited.
    fn wait_for(&self, what: &str, done: impl Fn() -> bool) {
        let start = Instant::now();
        while !done() {
            for (name, child) in &self.daemons {
                assert!(
                    alive(child.id() as libc::pid_t),
                    "{name} exited while waiting for {what}{}",
                    self.logs()
                );
            }
            assert!(
                start.elapsed() < PATIENCE,
                "no {what} after {PATIENCE:?}{}",
                self.logs()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Every job the controller knows, array tasks one by one once they have started.
    fn jobs(&self) -> Vec<Job> {
        let out = output(self.command("scontrol").args(["-o", "show", "job"]));
        assert!(
            out.status.success(),
            "scontrol: {}{}",
            text(&out.stderr),
            self.logs()
        );
        text(&out.stdout)
            .lines()
            .filter(|line| line.starts_with("JobId="))
            .map(|line| {
                line.split_whitespace()
                    .filter_map(|field| field.split_once('='))
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect()
            })
            .collect()
    }

    /// Waits until every job has ended or waits on one that failed, and returns them.
    fn settled_jobs(&self, what: &str, work: &Path) -> Vec<Job> {
        let start = Instant::now();
        loop {
            let jobs = self.jobs();
            if jobs
                .iter()
                .all(|j| ended(j) || j["Reason"] == "DependencyNeverSatisfied")
            {
                return jobs;
            }
            assert!(
                start.elapsed() < PATIENCE,
                "{what}: not after {PATIENCE:?}: {}{}",
                summary(&jobs),
                self.report(work)
            );
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    /// The daemons' logs and the jobs' output files in `work`.
    fn report(&self, work: &Path) -> String {
        let mut out = self.logs();
        let mut files: Vec<PathBuf> = [work.to_path_buf(), work.join("parts")]
            .iter()
            .filter_map(|d| std::fs::read_dir(d).ok())
            .flatten()
            .map(|e| e.unwrap().path())
            .filter(|p| {
                let name = p.file_name().unwrap().to_string_lossy();
                name.ends_with(".txt") || name.ends_with(".out")
            })
            .collect();
        files.sort();
        for file in files {
            out += &format!(
                "\n--- {} ---\n{}",
                file.display(),
                std::fs::read_to_string(&file).unwrap_or_default()
            );
        }
        out
    }

    /// Runs `script` with bash in `work` as a user at the cluster's login node would, with `env`;
    /// returns its standard output.
    fn bash(&self, work: &Path, script: &str, env: &[(&str, &str)]) -> String {
        let out = output(
            self.command("bash")
                .args(["-euo", "pipefail", "-c", script])
                .current_dir(work)
                .envs(env.iter().copied()),
        );
        assert!(
            out.status.success(),
            "{script}\n{}{}",
            text(&out.stderr),
            self.report(work)
        );
        text(&out.stdout)
    }

    /// The pids and command lines of the processes of this cluster: the daemons' and the jobs' all have
    /// its configuration in their environment.
    fn processes(&self) -> Vec<(libc::pid_t, String)> {
        let mark = format!("SLURM_CONF={}", self.conf.display());
        let mut out = Vec::new();
        for entry in std::fs::read_dir("/proc").unwrap().flatten() {
            let Ok(pid) = entry.file_name().to_string_lossy().parse::<libc::pid_t>() else {
                continue;
            };
            let Ok(environ) = std::fs::read(entry.path().join("environ")) else {
                continue;
            };
            if environ.split(|&b| b == 0).any(|var| var == mark.as_bytes()) {
                let cmdline = std::fs::read(entry.path().join("cmdline")).unwrap_or_default();
                out.push((pid, text(&cmdline).replace('\0', " ")));
            }
        }
        out
    }
}

impl Drop for Slurm {
    fn drop(&mut self) {
        for (_, child) in self.daemons.iter_mut().rev() {
            unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
            let start = Instant::now();
            while child.try_wait().unwrap().is_none() && start.elapsed() < Duration::from_secs(30) {
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
        // Job steps outlive slurmd (a restarted slurmd finds its jobs running): they and their processes
        // are killed here, and waited for (until gone or zombies of their new parent) before the
        // directory they work in is removed.
        let left = self.processes();
        for (pid, _) in &left {
            unsafe { libc::kill(*pid, libc::SIGKILL) };
        }
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(30) && left.iter().any(|(pid, _)| alive(*pid)) {
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

/// The CPU time `pid` has used, in clock ticks (1/100 s), or 0 once it is gone.
fn cpu_ticks(pid: libc::pid_t) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or_default()
        .split_whitespace()
        .collect();
    // utime and stime, the stat's 14th and 15th fields (the 3rd, the state, follows the command's ')').
    fields
        .get(11..13)
        .map_or(0, |t| t.iter().map(|v| v.parse::<u64>().unwrap_or(0)).sum())
}

/// Whether `pid` runs: it exists and is not a zombie.
fn alive(pid: libc::pid_t) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .is_ok_and(|stat| !stat.rsplit(')').next().unwrap().trim_start().starts_with('Z'))
}

/// `JobId JobState ExitCode Reason` of each job, a line each.
fn summary(jobs: &[Job]) -> String {
    let field = |job: &Job, key: &str| job.get(key).cloned().unwrap_or_default();
    jobs.iter()
        .map(|job| {
            format!(
                "\n  {} {} {} {} {}",
                field(job, "JobId"),
                field(job, "ArrayJobId") + "_" + &field(job, "ArrayTaskId"),
                field(job, "JobState"),
                field(job, "ExitCode"),
                field(job, "Reason")
            )
        })
        .collect()
}

fn state(job: &Job) -> &str {
    job.get("JobState").map_or("", String::as_str)
}

/// A job that will not run again (PENDING, RUNNING, COMPLETING and the like may).
fn ended(job: &Job) -> bool {
    matches!(
        state(job),
        "COMPLETED"
            | "FAILED"
            | "CANCELLED"
            | "TIMEOUT"
            | "NODE_FAIL"
            | "OUT_OF_MEMORY"
            | "BOOT_FAIL"
            | "DEADLINE"
    )
}

/// The jobs whose id, or whose array's id, is `id`.
fn of(jobs: &[Job], id: &str) -> Vec<Job> {
    jobs.iter()
        .filter(|j| j.get("JobId").is_some_and(|v| v == id) || j.get("ArrayJobId").is_some_and(|v| v == id))
        .cloned()
        .collect()
}

/// The job id in `sbatch`'s `Submitted batch job ID`.
fn submitted(stdout: &str) -> String {
    stdout
        .trim()
        .strip_prefix("Submitted batch job ")
        .unwrap_or_else(|| panic!("sbatch said {stdout:?}"))
        .to_string()
}

/// A directory for one frame: the repository's scenes, the doc's `render-part.sbatch` with `--array`
/// for `n` parts, and the single render of `opts` as `single.png`, whose bytes are returned.
fn frame(work: &Path, opts: &str, n: u32) -> Vec<u8> {
    std::fs::create_dir(work).unwrap();
    std::os::unix::fs::symlink(root().join("scenes"), work.join("scenes")).unwrap();
    let script = recipe("slurm");
    assert!(script.contains("\n#SBATCH --array=0-31\n"), "{script}");
    let script = script.replace(
        "\n#SBATCH --array=0-31\n",
        &format!("\n#SBATCH --array=0-{}\n", n - 1),
    );
    std::fs::write(work.join("render-part.sbatch"), script).unwrap();
    let single = work.join("single.png").display().to_string();
    run(&[
        &["render", SCENE, "-q", "-o", &single][..],
        &opts.split_whitespace().collect::<Vec<_>>(),
    ]
    .concat());
    std::fs::read(&single).unwrap()
}

const SCENE: &str = "scenes/distribution.p3f";

/// The merged image, which must be `single`.
fn assert_merged(slurm: &Slurm, work: &Path, single: &[u8], what: &str) {
    let merged = std::fs::read(work.join("dragon.png"))
        .unwrap_or_else(|e| panic!("{what}: no dragon.png: {e}{}", slurm.report(work)));
    assert!(
        merged == single,
        "{what}: the merged image differs from the single render"
    );
}

#[test]
fn slurm_runs_the_job_array_and_the_merge_as_written() {
    if !common::have("sbatch", &["--version"], "apt-get install slurm-wlm munge") {
        return;
    }
    let slurm = Slurm::start();
    let top = slurm.dir.path().to_path_buf();
    let n = 4;
    let parts = n.to_string();
    let env = |opts: &'static str| [("SCENE", SCENE), ("OPTS", opts), ("N", parts.as_str())];

    // The frame in 4 parts of about a second each (on 2 cores), then the merge job, as the doc submits them.
    let work = top.join("frame");
    let opts = "--width 160 --spp 64";
    let single = frame(&work, opts, n);
    slurm.bash(&work, &recipe("slurm-submit"), &env(opts));
    let jobs = slurm.settled_jobs("the array and the merge job", &work);
    assert_eq!(
        jobs.len(),
        n as usize + 1,
        "{n} tasks and the merge: {}",
        summary(&jobs)
    );
    assert!(
        jobs.iter()
            .all(|j| state(j) == "COMPLETED" && j["ExitCode"] == "0:0"),
        "a job failed: {}{}",
        summary(&jobs),
        slurm.report(&work)
    );
    assert_merged(&slurm, &work, &single, "the array");

    // A task cancelled mid-render (scancel: SIGTERM, as at a time limit or a pre-emption). These parts
    // take seconds: task 1 is cancelled once its whitted has rendered for 50 ms of CPU, past the scene's
    // load.
    let work = top.join("fault");
    let opts = "--width 320 --spp 64";
    let single = frame(&work, opts, n);
    let merge = submitted(&slurm.bash(&work, &recipe("slurm-submit"), &env(opts)));
    let array = slurm
        .jobs()
        .iter()
        .find(|j| j["JobName"] == "whitted-parts" && Path::new(&j["WorkDir"]) == work)
        .expect("the array is queued")["ArrayJobId"]
        .clone();
    slurm.wait_for("task 1's whitted to render", || {
        assert!(
            !work.join("parts/part-1.partial").exists(),
            "task 1 ended before it could be cancelled: the parts are too quick for this machine"
        );
        slurm.processes().iter().any(|(pid, cmd)| {
            cmd.starts_with("whitted render") && cmd.contains("parts/part-1.partial") && cpu_ticks(*pid) >= 5
        })
    });
    let cancel = output(slurm.command("scancel").arg(format!("{array}_1")));
    assert!(cancel.status.success(), "scancel: {}", text(&cancel.stderr));
    let jobs = slurm.settled_jobs("the array with a task cancelled", &work);
    let tasks = of(&jobs, &array);
    assert_eq!(tasks.len(), n as usize, "{}", summary(&tasks));
    for job in &tasks {
        let expected = if job["ArrayTaskId"] == "1" {
            "CANCELLED"
        } else {
            "COMPLETED"
        };
        assert_eq!(state(job), expected, "{}{}", summary(&tasks), slurm.report(&work));
    }
    let waits = &of(&jobs, &merge)[0];
    assert!(
        state(waits) == "PENDING" && waits["Reason"] == "DependencyNeverSatisfied",
        "the merge job after a cancelled task: {}",
        summary(&jobs)
    );
    assert!(!work.join("dragon.png").exists(), "the merge ran");

    // The merge job's command, run here, names the part: interrupted (SIGTERM: its finished tiles
    // kept) or missing (cancelled before its whitted caught signals).
    let submit = recipe("slurm-submit");
    let wrap = submit
        .split("--wrap \"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .unwrap();
    let out = output(slurm.command("bash").args(["-c", wrap]).current_dir(&work));
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{wrap}: {err}");
    let named = if work.join("parts/part-1.partial").exists() {
        "parts/part-1.partial holds".to_string()
    } else {
        format!("missing part(s) --tiles 1/{n}")
    };
    assert!(err.contains(&named), "{wrap} does not say \"{named}\": {err}");
    assert!(
        !work.join("dragon.png").exists(),
        "a refused merge wrote an image"
    );

    // The doc's rerun of the failed task, and the merge after it.
    let cancel = output(slurm.command("scancel").arg(&merge));
    assert!(cancel.status.success(), "scancel: {}", text(&cancel.stderr));
    let rerun = recipe("slurm-rerun");
    assert!(rerun.contains("--array=5,17 "), "{rerun}");
    let merge = submitted(&slurm.bash(&work, &rerun.replace("--array=5,17 ", "--array=1 "), &env(opts)));
    let jobs = slurm.settled_jobs("the rerun and its merge job", &work);
    let merged = of(&jobs, &merge);
    assert!(
        state(&merged[0]) == "COMPLETED" && merged[0]["ExitCode"] == "0:0",
        "the merge after the rerun: {}{}",
        summary(&jobs),
        slurm.report(&work)
    );
    assert_merged(&slurm, &work, &single, "the rerun");
}
